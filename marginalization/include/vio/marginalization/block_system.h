#pragma once
// The normal equations of a set of a ceres::Problem's residual blocks, the one
// assembly that both the Gauss-Newton step (estimator/gauss_newton.h) and the
// marginalization (marginalizer.h) use:
//
//   J^T J dx = -J^T r over the layout's blocks, on their tangent spaces, with
//   the loss functions applied as Ceres applies them (its Corrector);
//   assembled residual block by residual block (J_i^T J_j into the upper block
//   triangle, no sparse Jacobian); a marginalization prior without a loss
//   enters through its stored information Jp^T Jp (O(n^2), no dense Jacobian);
//   the `eliminated` blocks (landmarks: no residual touches two of them) are
//   Schur-complemented out one block at a time through their pseudo-inverse,
//   which leaves H and b over the `dense` blocks.
//
// The columns follow the layout's order and the sums the order of its
// residuals, never addresses, so the result does not depend on the heap
// layout. Blocks a residual touches outside the layout are held at their
// values (no column).
#include <memory>
#include <utility>
#include <vector>

#include <ceres/problem.h>

#include <Eigen/Core>

#include "vio/marginalization/linear_algebra.h"

namespace vio::marginalization {

/// Which variable parameter blocks get columns, and which residuals are summed.
struct BlockLayout {
  std::vector<double*> dense;       ///< kept in the reduced system, in column order
  std::vector<double*> eliminated;  ///< no residual touches two of them: Schur-eliminated one by one
  std::vector<ceres::ResidualBlockId> residuals;  ///< in summation order
};

/// The layout's normal equations at the current values, reduced to the dense
/// blocks. The residual-to-column structure is found once; Reduce() can be
/// called again after the values changed (not the blocks or residuals).
class BlockSystem {
 public:
  /// `threshold`: eigenvalues of an eliminated block's H below it count as
  /// zero in its pseudo-inverse.
  BlockSystem(ceres::Problem* problem, BlockLayout layout, const RankThreshold& threshold = {});
  ~BlockSystem();
  BlockSystem(const BlockSystem&) = delete;
  BlockSystem& operator=(const BlockSystem&) = delete;

  /// Becomes the system of another layout of the same problem (the next
  /// frame's window), as a new BlockSystem would, keeping the memory of its
  /// buffers: no reallocation, and no fresh pages to fault in, when the sizes
  /// repeat.
  void Relayout(BlockLayout layout);
  /// The same with another rank threshold (a marginalization's kept system).
  void Relayout(BlockLayout layout, const RankThreshold& threshold);
  ceres::Problem* problem() const;

  /// Assembles at the current values and eliminates; `cost` = 1/2 sum rho(|r|^2), or null
  /// when not wanted (a prior's cost is then not formed: one n^2 product fewer).
  /// False when a residual does not evaluate or gives a non-finite value.
  bool Reduce(double* cost);
  /// J^T J reduced to the dense columns; only its upper triangle is kept.
  const Eigen::MatrixXd& H() const;
  /// J^T r reduced to the dense columns.
  const Eigen::VectorXd& b() const;
  /// Moves H (made symmetric) and b out, without copying them; H() and b()
  /// are empty until the next Reduce().
  void MoveReducedTo(Eigen::MatrixXd* H, Eigen::VectorXd* b);
  /// Columns of the dense blocks.
  int dense_dim() const;
  /// Column offset and tangent size of dense block k.
  int dense_offset(int k) const;
  int dense_size(int k) const;
  /// The eliminated blocks' part of the step for a step `dx_dense` of the
  /// dense blocks (back-substitution): dx_e = -H_e^+ (b_e + W_e^T dx_dense);
  /// `dx` gets dx_dense, then every eliminated block's step in layout order.
  void BackSubstitute(const Eigen::VectorXd& dx_dense, Eigen::VectorXd* dx) const;
  /// 1/2 sum rho(|r|^2) at the current values, without Jacobians; false when
  /// a residual does not evaluate or is not finite.
  bool Cost(double* cost);
  /// The widest gap in `position` (one entry per dense block, -1: not
  /// counted) between two counted blocks that the reduced H couples: two
  /// blocks of one residual, or two dense blocks one eliminated block's Schur
  /// update ties together. A chain solver's bandwidth.
  int CouplingBandwidth(const std::vector<int>& position) const;
  /// For each dense block, the first and last dense block (by index) the
  /// reduced H couples it to (itself included): outside that span its rows
  /// of H are zero. With `counted` (one entry per dense block), only the
  /// counted blocks the reduced H couples it to: outside that span its rows
  /// are zero in the counted blocks' columns ((d, d) when it couples to none).
  std::vector<std::pair<int, int>> CoupledSpans(const std::vector<bool>& counted = {}) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vio::marginalization
