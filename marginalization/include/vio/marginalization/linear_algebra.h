#pragma once
// Dense linear algebra of marginalization (design paper, Theorem 2.2.2 and
// Algorithm 2), free of any Ceres type so tests and the "equivalence
// theorems" work can call it on plain matrices.
//
// A linearized least-squares cost over a tangent-space step dx,
//
//   || r + J dx ||^2 = dx^T H dx + 2 b^T dx + r^T r,   H = J^T J,  b = J^T r,
//
// is carried as its NormalEquations (H, b). Partitioning dx = [dx_K; dx_M]
// (kept first, marginalized last) and minimizing over dx_M gives
//
//   H* = H_KK - H_KM H_MM^+ H_MK,      b* = b_K - H_KM H_MM^+ b_M,
//
// (the Schur complement; ^+ is the eigenvalue-thresholded pseudo-inverse, so a
// marginalized direction the cost does not constrain is simply dropped). The
// prior is stored in square-root form r(dx_K) = r0 + Jp dx_K with
// Jp^T Jp = H* and Jp^T r0 = b*.
#include <vector>

#include <Eigen/Core>

namespace vio::marginalization {

/// When an eigenvalue of a symmetric positive semi-definite information
/// matrix counts as zero: lambda <= max(absolute, relative * lambda_max).
struct RankThreshold {
  /// Relative to the largest eigenvalue of the same matrix [-].
  double relative = 1e-12;
  /// Absolute floor [information units, 1 / (tangent unit)^2].
  double absolute = 1e-12;
};

/// How SqrtInformationFromHessian factors H.
enum class SqrtMethod {
  /// H = V diag(lambda) V^T: drops exactly the weakest directions; ~9 n^3
  /// flops (about 0.1 s for n = 400, 0.7 s for n = 700).
  kEigen,
  /// H = P^T L L^T P + remainder, the rank-revealing Cholesky with diagonal
  /// pivoting (LAPACK dpstrf's algorithm): it stops when the largest diagonal
  /// left is below the threshold, and the remainder is dropped; ~n^3 / 3
  /// flops. When every pivot of the unpivoted blocked Cholesky H = L L^T
  /// clears the threshold (nothing to drop), that factor is used: the same
  /// prior up to an orthogonal transform of its rows, 3-5x faster again. Falls
  /// back to kEigen when the factor does not give H back (H indefinite beyond
  /// round-off).
  kPivotedCholesky,
  /// kPivotedCholesky without the unpivoted attempt: for an H expected to be
  /// rank-deficient (a sliding window's marginal usually is when the previous
  /// one was), where that attempt costs a whole factorization and then fails
  /// its pivot test. Any H gives the same prior as kPivotedCholesky up to an
  /// orthogonal transform of its rows.
  kPivotedCholeskyOnly,
};

/// Gauss-Newton normal equations of a linearized cost: H = J^T J, b = J^T r.
struct NormalEquations {
  Eigen::MatrixXd H;  ///< information (Hessian approximation), n x n
  Eigen::VectorXd b;  ///< information vector J^T r (gradient), n
};

/// Square-root form of a linearized prior: r(dx) = residual + sqrt_information * dx.
struct SqrtInformation {
  Eigen::MatrixXd sqrt_information;  ///< Jp, rank x n (rank = kept eigenvalues)
  Eigen::VectorXd residual;          ///< r0, rank
  /// Jp^T Jp, n x n: the information the factor carries (for kPivotedCholesky
  /// the factored H itself, which Jp^T Jp reproduces to 1e-13 relative).
  Eigen::MatrixXd information;
};

/// Whether every entry of `m` is finite, as Eigen's allFinite() says, in one
/// vectorized pass (the sum of m * 0 is zero exactly when no entry is infinite
/// or NaN) instead of a comparison per entry: for the n x n matrices a
/// marginalization validates.
inline bool AllFinite(const Eigen::Ref<const Eigen::MatrixXd>& m) { return (m.array() * 0.0).sum() == 0.0; }

/// Pseudo-inverse of a symmetric PSD matrix via its eigen-decomposition;
/// eigenvalues at or below `threshold` are treated as zero.
Eigen::MatrixXd PseudoInverse(const Eigen::MatrixXd& H, const RankThreshold& threshold = {});
/// PseudoInverse into `H_inv` (the same values); for a 3x3 H (a landmark's
/// block) without a heap allocation once H_inv has that size.
void PseudoInverseInto(const Eigen::MatrixXd& H, const RankThreshold& threshold, Eigen::MatrixXd* H_inv);

/// Schur complement that removes the trailing `marg_dim` variables of (H, b):
/// H is (keep_dim + marg_dim) square, kept variables first. Throws
/// std::invalid_argument when the sizes disagree.
NormalEquations SchurComplement(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, int keep_dim,
                                int marg_dim, const RankThreshold& threshold = {});

/// Same as SchurComplement for a symmetric H whose trailing blocks of sizes
/// `marg_block_dims` are mutually uncoupled (H is zero between any two of
/// them), so H_MM is block-diagonal and is pseudo-inverted block by block,
/// each update touching only the kept rows the block couples to: cost linear
/// in the number of blocks (landmarks) instead of cubic in their total size.
NormalEquations SchurComplementOfUncoupledBlocks(const Eigen::MatrixXd& H, const Eigen::VectorXd& b,
                                                 int keep_dim,
                                                 const std::vector<int>& marg_block_dims,
                                                 const RankThreshold& threshold = {});

/// Square root (Jp, r0) of (H, b) with Jp^T Jp = H and Jp^T r0 = b, dropping
/// the factors whose eigenvalue (kEigen) or pivot (kPivotedCholesky) is below the
/// threshold (b's component there is lost, as it must be):
///   kEigen:       H = V diag(l) V^T,     Jp = diag(sqrt(l)) V^T,  r0 = diag(1/sqrt(l)) V^T b;
///   kPivotedCholesky: H = P^T L L^T P (+ dropped remainder), Jp = L^T P,  r0 = L^-1 P b.
/// Zero rows when nothing survives the threshold.
SqrtInformation SqrtInformationFromHessian(const Eigen::MatrixXd& H, const Eigen::VectorXd& b,
                                           const RankThreshold& threshold = {},
                                           SqrtMethod method = SqrtMethod::kEigen);

}  // namespace vio::marginalization
