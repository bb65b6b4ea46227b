#pragma once
// A landmark measured in a state's body frame: the local map's summary of the
// stereo observations of frames it dropped (local_map.h), each taken relative
// to the keyframe it keeps as their anchor.
//
// Parameter blocks: pose [p_w_b, q_w_b] (7) of the anchor, landmark p_w_l (3).
//   p_b = R_w_b^T (p_w_l - p_w_b),   r = L (p_b - p_b_hat)
// with p_b_hat the mean of the summarized observations and L^T L their
// information per observation (AnchoredPointSummary). Jacobians (pose tangent [dp, dtheta],
// q <- q Exp(dtheta)):
//   dr/dp_w_b = -L R_w_b^T,   dr/dtheta = L [p_b]x,   dr/dp_w_l = L R_w_b^T.
#include <ceres/sized_cost_function.h>

#include <Eigen/Core>

#include "vio/marginalization/tangent_cost_function.h"

namespace vio {

/// The Gauss-Newton summary of whitened observations e_i(p_b) of one point in a body frame:
/// each linearized at p_b0 with Jacobian J_i contributes information J_i^T J_i and the mean it
/// alone gives; mean() is where 1/2 sum |e_i|^2 is least to second order. The factor weighs the
/// summary as one observation of that mean (SqrtInformation: of the information over the count):
/// the frames' poses relative to the keyframe are held as estimated, and their errors, which all
/// the views share, bound what the views know together; summed as independent (the whole
/// information) the map's second lap in the simulator's room came out worse than its first.
class AnchoredPointSummary {
 public:
  /// One whitened residual e0 at p_b0 with de/dp_b = J.
  void Add(const Eigen::Vector3d& p_b0, const Eigen::Vector3d& e0, const Eigen::Matrix3d& J);
  /// Adds `other`, a summary of the same point in a frame o with p = R p_o + t in this one.
  void Absorb(const AnchoredPointSummary& other, const Eigen::Matrix3d& R, const Eigen::Vector3d& t);
  int count() const { return count_; }
  const Eigen::Matrix3d& information() const { return information_; }
  /// False when the information is not positive definite (no usable mean).
  bool Usable() const;
  Eigen::Vector3d mean() const;
  /// Upper-triangular L with L^T L = information() / count(): one observation's weight.
  Eigen::Matrix3d SqrtInformation() const;

 private:
  Eigen::Matrix3d information_ = Eigen::Matrix3d::Zero();
  Eigen::Vector3d information_mean_ = Eigen::Vector3d::Zero();  ///< sum J^T J p_b_i
  int count_ = 0;
};

class AnchoredPointFactor final : public ceres::SizedCostFunction<3, 7, 3>,
                                  public marginalization::TangentCostFunction {
 public:
  AnchoredPointFactor(const Eigen::Vector3d& p_b_hat, const Eigen::Matrix3d& sqrt_information)
      : p_b_hat_(p_b_hat), sqrt_information_(sqrt_information) {}

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  bool EvaluateOnTangents(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  bool EvaluateImpl(double const* const* parameters, double* residuals, double** jacobians, bool on_tangents) const;

  Eigen::Vector3d p_b_hat_;
  Eigen::Matrix3d sqrt_information_;
};

}  // namespace vio
