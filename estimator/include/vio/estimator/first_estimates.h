#pragma once
// First-estimate Jacobians (FEJ; Huang, Mourikis, Roumeliotis 2008-2010).
//
// A marginalization prior is linearized once, at x0, and never again. If the
// other factors on the same blocks are relinearized at later estimates, the
// Jacobians of one cost are taken at two points, and the information gains
// directions that no measurement observes (for VIO: yaw about gravity; global
// position stays unobservable at any point). FEJ evaluates the Jacobians of
// every factor on a held block at that block's first estimate, the value it
// had when it first entered a prior, while residuals stay at the current
// estimate. Then every Jacobian of the window is taken at one point per
// block, and the 4-dimensional unobservable subspace stays in the null space
// of the window's information.
//
// Held blocks (Window with model.fej): every state pose, state speed/bias and
// landmark block from the moment it first enters a prior (the first state's
// prior, or a marginalization prior on its Markov blanket) until it leaves the
// window, at the value it had then. A block in a second prior keeps its first
// estimate: the new prior is re-expressed at it (marginalizer.h). Blocks in no
// prior (the newest states, landmarks only states see) are relinearized as
// usual.
#include <map>
#include <memory>
#include <vector>

#include <ceres/cost_function.h>
#include <ceres/manifold.h>

#include "vio/estimator/types.h"

namespace vio {

/// Which block of the window a factor parameter is.
struct BlockKey {
  enum class Kind { kPose, kSpeedBias, kLandmark, kTimeOffset, kExtrinsics };
  Kind kind = Kind::kPose;
  std::int64_t id = 0;  ///< StateId or LandmarkId value

  static BlockKey Pose(StateId s) { return {Kind::kPose, s.value}; }
  static BlockKey SpeedBias(StateId s) { return {Kind::kSpeedBias, s.value}; }
  static BlockKey Landmark(LandmarkId l) { return {Kind::kLandmark, l.value}; }
  static BlockKey TimeOffset() { return {Kind::kTimeOffset, 0}; }
  static BlockKey Extrinsics() { return {Kind::kExtrinsics, 0}; }
  bool operator<(const BlockKey& o) const { return kind != o.kind ? kind < o.kind : id < o.id; }
  bool operator==(const BlockKey& o) const { return kind == o.kind && id == o.id; }
  /// Whether it is one of state `s`'s blocks (its pose or speed/bias).
  bool IsOf(StateId s) const { return (kind == Kind::kPose || kind == Kind::kSpeedBias) && id == s.value; }
  bool IsCalibration() const { return kind == Kind::kTimeOffset || kind == Kind::kExtrinsics; }
};

/// The first estimates of the held blocks.
class FirstEstimates {
 public:
  /// Holds `values` (`size` doubles, ambient) as the block's first estimate
  /// unless it already has one.
  void Hold(const BlockKey& key, const double* values, int size);
  /// The held values, nullptr when the block is not held.
  const double* Find(const BlockKey& key) const;
  void Release(const BlockKey& key) { values_.erase(key); }
  int size() const { return static_cast<int>(values_.size()); }

 private:
  std::map<BlockKey, std::vector<double>> values_;
};

/// A factor whose Jacobians on held blocks are evaluated at their first
/// estimates (the other blocks at their current values, as usual); the
/// residual is the wrapped factor's at the current values. Jacobians come
/// back for Ceres' ambient convention: on a manifold block the tangent
/// Jacobian at the first estimate, J_fe * PlusJacobian(x_fe), is multiplied by
/// MinusJacobian(x), so that Ceres' product with PlusJacobian(x) gives it back.
class FejCostFunction final : public ceres::CostFunction {
 public:
  /// One parameter block of the wrapped factor.
  struct Parameter {
    BlockKey key;
    const ceres::Manifold* manifold = nullptr;  ///< not owned; nullptr = Euclidean
  };

  /// Takes ownership of `wrapped`; `parameters` in its parameter order.
  FejCostFunction(ceres::CostFunction* wrapped, std::vector<Parameter> parameters,
                  std::shared_ptr<const FirstEstimates> first_estimates);

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  std::unique_ptr<ceres::CostFunction> wrapped_;
  std::vector<Parameter> parameters_;
  std::shared_ptr<const FirstEstimates> first_estimates_;
};

}  // namespace vio
