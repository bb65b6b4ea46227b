#pragma once
// Marginalization on a live ceres::Problem (design paper, Algorithm 2), using
// the problem's own residual blocks: no second assembly of the cost.
//
//   1. C2 = every residual block touching a block to marginalize (x_M);
//      the Markov blanket x_K = the other parameter blocks those touch.
//   2-3. The normal equations of C2 at the current values on the TANGENT
//      space of every block, loss functions applied as Ceres applies them,
//      with x_M removed by the Schur complement: landmark-like blocks that
//      share no residual with another marginalized block block by block, as
//      the Gauss-Newton step eliminates landmarks (BlockSystem, the one
//      assembly both use: block_system.h), the rest densely (SchurComplement).
//   4. (H*, b*) -> square root (Jp, r0) (SqrtInformationFromHessian) ->
//      MarginalizationPrior over x_K with x0 = the current values of x_K.
//
// Constant parameter blocks are treated as KNOWN: they never get a Jacobian
// column. A constant block in the blanket is left out of the prior (its
// residuals still inform the variable blanket blocks, conditioned on its
// current value); if it is made variable later the prior says nothing about
// it. A constant block in `to_marginalize` is conditioned on, not integrated
// out: its residuals still feed the prior on the blanket.
#include <memory>
#include <vector>

#include <ceres/problem.h>

#include "vio/marginalization/linear_algebra.h"
#include "vio/marginalization/marginalization_prior.h"

namespace vio::marginalization {

class BlockSystem;

struct MarginalizationOptions {
  /// Eigenvalues of H_MM (when pseudo-inverting it) and eigenvalues / pivots
  /// of the marginal H* (when taking its square root) below this are zero.
  RankThreshold rank_threshold;
  /// Factorization of H* into the prior's square root. The blanket of a
  /// sliding window easily has 300-700 dimensions, where kEigen costs
  /// 0.1-0.7 s and kPivotedCholesky 15-20x less.
  SqrtMethod sqrt_method = SqrtMethod::kPivotedCholesky;
  /// The order in which residual blocks are summed, when not empty (it must
  /// hold every residual block touching a marginalized block). Empty: the
  /// problem's order, which Ceres' block removal makes depend on addresses.
  std::vector<ceres::ResidualBlockId> residual_order;
  /// residual_order holds exactly the residual blocks touching a marginalized block (the caller keeps
  /// that bookkeeping): the problem is not asked for them. Without Ceres' enable_fast_removal the
  /// problem keeps no residuals per block, and asking scans every residual once per block.
  bool residual_order_is_exact = false;
  /// The kept blocks' column order, when not empty: the kept blocks listed
  /// here come first, in this order, then the others in order of first
  /// appearance. A window passes its state blocks with the poses last and the
  /// block every observation touches (the time offset) after them, right
  /// before the marginalized states' poses: the poses seeing one landmark are
  /// then mostly one contiguous range, and its Schur update one rank update in
  /// place.
  std::vector<const double*> kept_order;
  /// First-estimate Jacobians (FEJ), when not empty (then as long as
  /// kept_order): the first estimate of each kept_order block (AmbientSize
  /// values), or nullptr when it has none; a kept block not listed has none.
  /// The prior is linearized at the current values as always, then
  /// re-expressed at the first estimates, x0_i = x_fe_i,
  /// r0 <- r0 + Jp_i (x_fe_i ⊟ x_i) (exact at x_fe for the linear model), and
  /// holds its Jacobian at x0 (MarginalizationPrior::HoldJacobianAtLinearizationPoint).
  std::vector<const double*> first_estimates;
  /// A system of the same problem to assemble in (re-laid out, its buffers
  /// reused from one marginalization to the next), or nullptr for a new one.
  BlockSystem* system = nullptr;
};

struct MarginalizationResult {
  /// Prior over `kept_blocks`; null when no variable block of the blanket
  /// keeps any information (empty blanket, or H* numerically zero).
  std::unique_ptr<MarginalizationPrior> prior;
  /// The variable Markov-blanket blocks, in the prior's parameter order
  /// (empty when `prior` is null).
  std::vector<double*> kept_blocks;
  /// Every residual block touching a marginalized block (folded into the
  /// prior; removing the marginalized parameter blocks removes them).
  std::vector<ceres::ResidualBlockId> marginalized_residual_blocks;
};

/// Computes the prior that marginalizing `to_marginalize` leaves on its Markov
/// blanket, without changing the problem (the problem is not const: Ceres
/// hands out its blocks through non-const accessors).
/// Duplicates in `to_marginalize` are ignored. Throws std::invalid_argument if
/// a block is not in the problem or first_estimates is neither empty nor as
/// long as kept_order, std::runtime_error if evaluation fails.
MarginalizationResult ComputeMarginalization(ceres::Problem* problem,
                                             const std::vector<double*>& to_marginalize,
                                             const MarginalizationOptions& options = {});

/// ComputeMarginalization, then removes the `to_marginalize` parameter blocks
/// (and with them every residual block touching them) and adds the prior.
/// Returns the prior's residual block, or nullptr when there is no prior.
/// The problem must own its cost functions (Ceres' default
/// Problem::Options::cost_function_ownership = TAKE_OWNERSHIP).
ceres::ResidualBlockId MarginalizeBlocks(ceres::Problem* problem,
                                         const std::vector<double*>& to_marginalize,
                                         const MarginalizationOptions& options = {});

}  // namespace vio::marginalization
