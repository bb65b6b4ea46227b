#pragma once
// One exact Gauss-Newton step on a ceres::Problem (paper §2.2): linearize every
// residual at the current values (each cost function evaluated, loss functions
// applied as Ceres applies them, Jacobians on the tangent spaces), solve the normal
// equations J^T J dx = -J^T r without damping, and apply x <- x ⊞ dx. The step
// is always taken: no trust region, no line search; the caller may only undo a
// step whose end point does not evaluate (UndoStep).
//
// The columns are laid out by the caller (the window: states and landmarks by
// id), never by address, so the result does not depend on the heap layout.
// Mutually uncoupled blocks (landmarks, which no residual ties to another
// landmark) are eliminated first, one block at a time (Schur complement); the
// reduced system over the rest is solved by Cholesky, a chain of speed/bias
// blocks first when its band is narrow (chain_solve.h), the rest densely.
//
// The normal equations and the elimination are marginalization::BlockSystem
// (block_system.h), the one assembly the marginalization uses too: per
// residual block, J_i^T J_j into the upper block triangle, no sparse Jacobian;
// a marginalization prior through its stored information Jp^T Jp.
// GaussNewtonSolver keeps that structure and its buffers across the steps of
// one solve, and its buffers across solves (Relayout: the window keeps one).
#include <memory>
#include <vector>

#include <ceres/problem.h>

#include <Eigen/Core>

namespace vio {

/// Which variable parameter blocks the step solves for, in column order.
struct GaussNewtonLayout {
  std::vector<double*> dense;       ///< solved densely (states, landmarks tied by a prior)
  std::vector<double*> eliminated;  ///< no residual touches two of them: Schur-eliminated one by one
  /// Indices into `dense` of a chain solved first (speed/bias blocks in state
  /// order, which only IMU factors between neighbours tie): when the reduced
  /// system couples them within a narrow band, they are eliminated by a
  /// block-banded Cholesky before the dense solve of the rest (same step up
  /// to round-off, far fewer flops); otherwise ignored.
  std::vector<int> chain;
  /// Every residual block of the problem, in summation order (Ceres' own
  /// order changes with addresses once blocks were removed).
  std::vector<ceres::ResidualBlockId> residuals;
};

/// What one step did.
struct GaussNewtonStep {
  bool ok = false;         ///< false: evaluation failed or the system is singular; nothing was changed
  double cost = 0;         ///< cost at the linearization point, 1/2 |r|^2 (loss applied)
  double step_norm = 0;    ///< |dx| on the tangent space
  double values_norm = 0;  ///< |x| of the blocks before the step (ambient values)
};

/// The Gauss-Newton system at the current values with the eliminated blocks
/// Schur-complemented out: H dx = -b over the layout's dense columns (in
/// layout order, tangent spaces). H is the window's information about the
/// dense blocks.
struct ReducedSystem {
  Eigen::MatrixXd H;  ///< J^T J reduced to the dense columns
  Eigen::VectorXd b;  ///< J^T r reduced to the dense columns
};

/// Linearizes as TakeGaussNewtonStep does, without stepping; false when the
/// layout is empty or evaluation fails.
bool ReducedNormalEquations(ceres::Problem* problem, const GaussNewtonLayout& layout, ReducedSystem* system);

/// Successive Gauss-Newton steps on one problem whose blocks and residuals do
/// not change between the steps (the values do): the residual-to-column
/// structure is found once per layout, the buffers are reused.
class GaussNewtonSolver {
 public:
  GaussNewtonSolver(ceres::Problem* problem, GaussNewtonLayout layout);
  ~GaussNewtonSolver();
  GaussNewtonSolver(const GaussNewtonSolver&) = delete;
  GaussNewtonSolver& operator=(const GaussNewtonSolver&) = delete;

  /// Solves for `layout` from now on, as a new solver would, keeping the
  /// buffers' memory (a window's successive solves have layouts of about one
  /// size). UndoStep() is not available until the next Step().
  void Relayout(GaussNewtonLayout layout);

  /// One undamped step on the layout's blocks (see TakeGaussNewtonStep).
  GaussNewtonStep Step();
  /// Restores the values from before the last successful Step() (for a step
  /// whose end point does not evaluate, e.g. a landmark moved behind a camera).
  void UndoStep();
  /// 1/2 |r|^2 at the current values (see EvaluateCost).
  bool Cost(double* cost);
  /// The reduced system at the current values (see ReducedNormalEquations).
  bool Reduce(ReducedSystem* system);

 private:
  struct System;
  std::unique_ptr<System> system_;
};

/// Takes one undamped Gauss-Newton step on the blocks of `layout`; every
/// other block is held at its value.
GaussNewtonStep TakeGaussNewtonStep(ceres::Problem* problem, const GaussNewtonLayout& layout);

/// 1/2 |r|^2 of the layout's residuals at the current values, loss applied;
/// false when evaluation fails.
bool EvaluateCost(ceres::Problem* problem, const GaussNewtonLayout& layout, double* cost);

}  // namespace vio
