#pragma once
// A Gaussian over a stacked state whose blocks may live on manifolds, as the
// filters of the design paper (ch. 4.3, appendix Algorithms 5-12) carry it,
// and how far apart two such Gaussians are.
//
// The state is an ordered list of blocks (StateLayout). The mean is stored in
// the blocks' ambient parameterization, stacked; the covariance is over the
// stacked tangent spaces at the mean, in the same block order. A block
// without a manifold is Euclidean: x ⊞ d = x + d, y ⊟ x = y - x. A block
// with a ceres::Manifold uses its Plus / Minus (e.g. the pose block).
#include <ceres/manifold.h>

#include <Eigen/Core>
#include <vector>

namespace vio::marginalization {

/// One block of a stacked state.
struct StateBlock {
  int ambient_size = 0;                       ///< doubles in the mean
  int tangent_size = 0;                       ///< rows / columns in the covariance
  const ceres::Manifold* manifold = nullptr;  ///< not owned; nullptr = Euclidean
};

/// The ordered blocks of a stacked state, with ⊞ / ⊟ over the whole stack.
class StateLayout {
 public:
  /// A Euclidean block of `size` (>= 0).
  StateLayout& AddEuclidean(int size);
  /// A block on `manifold` (not owned; must outlive the layout).
  StateLayout& AddManifold(const ceres::Manifold* manifold);
  /// Appends every block of `other`.
  StateLayout& Append(const StateLayout& other);
  /// The `count` blocks starting at block `first`.
  StateLayout Slice(int first, int count) const;

  const std::vector<StateBlock>& blocks() const { return blocks_; }
  int AmbientSize() const { return ambient_size_; }
  int TangentSize() const { return tangent_size_; }

  /// x ⊞ delta, block by block (x: AmbientSize(), delta: TangentSize()).
  Eigen::VectorXd Plus(const Eigen::VectorXd& x, const Eigen::VectorXd& delta) const;
  /// y ⊟ x, block by block (y, x: AmbientSize(); result: TangentSize()).
  Eigen::VectorXd Minus(const Eigen::VectorXd& y, const Eigen::VectorXd& x) const;

 private:
  std::vector<StateBlock> blocks_;
  int ambient_size_ = 0;
  int tangent_size_ = 0;
};

/// N(mean, covariance) over a StateLayout: mean ambient, covariance tangent.
struct Gaussian {
  Eigen::VectorXd mean;
  Eigen::MatrixXd covariance;
};

/// How far two Gaussians over the same layout are apart, relative.
struct Deviation {
  /// |mean_a ⊟ mean_b| / max(|mean_b ⊟ x*|, sqrt(trace(cov_b))): relative to
  /// the step from the linearization point x*, or, when the step is smaller
  /// (it is zero for augmentation and propagation), to the state's total
  /// standard deviation [-].
  double mean = 0.0;
  /// ||cov_a - cov_b||_F / ||cov_b||_F [-].
  double covariance = 0.0;
};

/// The Deviation of `a` from the reference `b`; `linearization_point` is the
/// x* both were computed at. Throws std::invalid_argument on size mismatch.
Deviation Compare(const Gaussian& a, const Gaussian& b, const StateLayout& layout,
                  const Eigen::VectorXd& linearization_point);

/// The field-wise maximum; a NaN field stays NaN (a failed check never hides).
Deviation Max(const Deviation& a, const Deviation& b);

}  // namespace vio::marginalization
