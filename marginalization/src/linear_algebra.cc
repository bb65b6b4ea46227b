#include "vio/marginalization/linear_algebra.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <glog/logging.h>

namespace vio::marginalization {
namespace {

// Largest relative error ||Jp^T Jp - H||_F / ||H||_F the Cholesky square roots may leave.
constexpr double kReconstructionTolerance = 1e-13;
// Probe vectors that estimate that error.
constexpr int kProbes = 4;

/// The eigen-pairs of a symmetric PSD matrix whose eigenvalue survives the
/// threshold: H ~= eigenvectors * diag(eigenvalues) * eigenvectors^T.
struct SignificantEigenpairs {
  Eigen::VectorXd eigenvalues;   ///< r, all > threshold
  Eigen::MatrixXd eigenvectors;  ///< n x r, orthonormal columns
};

void RequireFinite(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, const char* where) {
  if (!AllFinite(H) || !AllFinite(b)) {
    throw std::invalid_argument(std::string(where) +
                                ": information matrix or vector is not finite");
  }
}

void RequireSizes(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, int keep_dim, int marg_dim,
                  const char* where) {
  const bool ok = keep_dim >= 0 && marg_dim >= 0 && H.rows() == H.cols() &&
                  H.rows() == keep_dim + marg_dim && b.size() == H.rows();
  if (!ok) {
    std::ostringstream message;
    message << where << ": H is " << H.rows() << "x" << H.cols() << ", b has " << b.size()
            << " rows, but keep_dim = " << keep_dim << " and marg_dim = " << marg_dim;
    throw std::invalid_argument(message.str());
  }
}

Eigen::MatrixXd SymmetricPart(const Eigen::MatrixXd& H) {
  return 0.5 * (H + H.transpose());
}

/// Eigenvalues at or below this are dropped as zero.
double EigenvalueCutoff(double largest_eigenvalue, const RankThreshold& threshold) {
  return std::max(threshold.absolute, threshold.relative * std::max(largest_eigenvalue, 0.0));
}

/// PseudoInverse of a 3x3 block (every landmark of a Schur elimination) on
/// fixed-size matrices, without heap allocation: the closed-form inverse when
/// no eigenvalue can be below the cutoff, else the same decomposition and
/// cutoff as DecomposeSignificant.
Eigen::Matrix3d PseudoInverse3(const Eigen::Matrix3d& H, const RankThreshold& threshold) {
  const Eigen::Matrix3d S = 0.5 * (H + H.transpose());
  // Clearly definite (Sylvester's minors), with lambda_min >= det / trace^2
  // above the cutoff (relative to lambda_max <= trace): no eigenvalue is
  // dropped and the pseudo-inverse is the inverse, in closed form.
  const double trace = S.trace();
  const double det = S.determinant();
  if (S(0, 0) > 0.0 && S(0, 0) * S(1, 1) - S(0, 1) * S(0, 1) > 0.0 &&
      det > EigenvalueCutoff(trace, threshold) * trace * trace) {
    return S.inverse();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(S);
  CHECK(solver.info() == Eigen::Success) << "eigen-decomposition of a finite symmetric matrix failed";
  const Eigen::Vector3d& lambda = solver.eigenvalues();
  const double cutoff = EigenvalueCutoff(lambda.maxCoeff(), threshold);
  const Eigen::Vector3d inverse = (lambda.array() > cutoff).select(lambda.cwiseInverse(), 0.0);
  return solver.eigenvectors() * inverse.asDiagonal() * solver.eigenvectors().transpose();
}

SignificantEigenpairs DecomposeSignificant(const Eigen::MatrixXd& H,
                                           const RankThreshold& threshold) {
  SignificantEigenpairs result;
  if (H.rows() == 0) {
    return result;
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(SymmetricPart(H));
  CHECK(solver.info() == Eigen::Success)
      << "eigen-decomposition of a finite symmetric matrix failed";
  const Eigen::VectorXd& lambda = solver.eigenvalues();  // ascending
  const double cutoff = EigenvalueCutoff(lambda.maxCoeff(), threshold);
  int first_kept = 0;
  while (first_kept < lambda.size() && lambda(first_kept) <= cutoff) {
    ++first_kept;
  }
  const int rank = static_cast<int>(lambda.size()) - first_kept;
  result.eigenvalues = lambda.tail(rank);
  result.eigenvectors = solver.eigenvectors().rightCols(rank);
  return result;
}

/// Throws unless H is exactly zero between any two of the trailing blocks.
void RequireUncoupled(const Eigen::MatrixXd& H, int keep_dim, const std::vector<int>& block_dims) {
  int row = keep_dim;
  for (const int rows : block_dims) {
    const int col = row + rows;
    const int cols = static_cast<int>(H.cols()) - col;
    if (cols > 0 && !H.block(row, col, rows, cols).isZero(0.0)) {
      throw std::invalid_argument(
          "SchurComplementOfUncoupledBlocks: marginalized blocks are coupled (H_MM is not "
          "block-diagonal)");
    }
    row = col;
  }
}

/// marginal -= the Schur update of the block [offset, offset + dim) of the
/// symmetric (H, b), restricted to the kept rows that block couples to.
void EliminateBlock(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, int offset, int dim,
                    const RankThreshold& threshold, NormalEquations* marginal) {
  const int keep_dim = static_cast<int>(marginal->H.rows());
  std::vector<int> coupled_rows;
  for (int row = 0; row < keep_dim; ++row) {
    if (!H.block(row, offset, 1, dim).isZero(0.0)) {
      coupled_rows.push_back(row);
    }
  }
  if (coupled_rows.empty()) {
    return;
  }
  const Eigen::MatrixXd H_KM = H(coupled_rows, Eigen::seqN(offset, dim));
  const Eigen::MatrixXd H_KM_H_MM_inv =
      H_KM * PseudoInverse(H.block(offset, offset, dim, dim), threshold);
  marginal->H(coupled_rows, coupled_rows) -= H_KM_H_MM_inv * H_KM.transpose();
  marginal->b(coupled_rows) -= H_KM_H_MM_inv * b.segment(offset, dim);
}

/// Jp^T Jp, formed once (n^2 rank flops).
Eigen::MatrixXd GramOf(const Eigen::MatrixXd& Jp) {
  Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(Jp.cols(), Jp.cols());
  gram.selfadjointView<Eigen::Lower>().rankUpdate(Jp.transpose());
  gram.triangularView<Eigen::StrictlyUpper>() = gram.transpose();
  return gram;
}

SqrtInformation SqrtByEigen(const Eigen::MatrixXd& H, const Eigen::VectorXd& b,
                            const RankThreshold& threshold) {
  const SignificantEigenpairs eig = DecomposeSignificant(H, threshold);
  const Eigen::MatrixXd V_transpose = eig.eigenvectors.transpose();
  const Eigen::VectorXd sqrt_lambda = eig.eigenvalues.cwiseSqrt();
  SqrtInformation sqrt{sqrt_lambda.asDiagonal() * V_transpose,
                       sqrt_lambda.cwiseInverse().asDiagonal() * (V_transpose * b), Eigen::MatrixXd()};
  sqrt.information = GramOf(sqrt.sqrt_information);
  return sqrt;
}

/// Fixed +-1 probe vectors (n x kProbes), the same for every call: for any E,
/// the mean of |E v|^2 over such v is ||E||_F^2.
Eigen::MatrixXd ProbeVectors(Eigen::Index n) {
  Eigen::MatrixXd V(n, kProbes);
  std::uint64_t state = 0x9E3779B97F4A7C15ULL;
  for (Eigen::Index k = 0; k < V.size(); ++k) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;  // Knuth's MMIX LCG
    V.data()[k] = (state >> 63) != 0 ? 1.0 : -1.0;
  }
  return V;
}

/// Whether Jp^T Jp gives H back to kReconstructionTolerance (relative,
/// Frobenius), or to `dropped`, the most a remainder the factorization dropped
/// may hold, when that is more; estimated on kProbes probe vectors: O(n^2)
/// instead of the n^3 of forming Jp^T Jp. The failure it guards against
/// (amplified round-off after a round-off pivot) is many orders above both.
bool Reproduces(const Eigen::MatrixXd& Jp, const Eigen::MatrixXd& H, double dropped = 0.0) {
  const Eigen::MatrixXd V = ProbeVectors(H.cols());
  const Eigen::MatrixXd JpV = Jp * V;
  const Eigen::MatrixXd error = Jp.transpose() * JpV - H * V;
  return error.norm() <= std::max(kReconstructionTolerance * H.norm(), dropped) * std::sqrt(static_cast<double>(kProbes));
}

/// Jp = L^T, r0 = L^-1 b from the blocked Cholesky factor H = L L^T when
/// every pivot L_ii^2 clears the threshold (relative to H's largest diagonal,
/// the first pivot of the pivoted factorization): then nothing is dropped, and
/// this square root differs from the pivoted one only by an orthogonal
/// transform of its rows (the same prior). Empty when H is not that clearly
/// definite.
std::optional<SqrtInformation> SqrtByCholesky(const Eigen::MatrixXd& H_symmetric, const Eigen::VectorXd& b,
                                              const RankThreshold& threshold) {
  const Eigen::LLT<Eigen::MatrixXd> llt(H_symmetric);
  if (llt.info() != Eigen::Success) return std::nullopt;
  const double cutoff = EigenvalueCutoff(H_symmetric.diagonal().maxCoeff(), threshold);
  if (!(llt.matrixLLT().diagonal().array().square() > cutoff).all()) return std::nullopt;
  SqrtInformation sqrt{llt.matrixU(), llt.matrixL().solve(b), Eigen::MatrixXd()};
  if (!Reproduces(sqrt.sqrt_information, H_symmetric)) return std::nullopt;
  return sqrt;
}

/// Swaps variables k < j of the symmetric matrix held in A's lower triangle.
void SymmetricSwap(Eigen::MatrixXd& A, Eigen::Index k, Eigen::Index j) {
  const Eigen::Index n = A.rows();
  std::swap(A(k, k), A(j, j));
  A.row(k).head(k).swap(A.row(j).head(k));
  A.col(k).tail(n - j - 1).swap(A.col(j).tail(n - j - 1));
  for (Eigen::Index i = k + 1; i < j; ++i) std::swap(A(i, k), A(j, i));
}

/// Rank-revealing Cholesky with diagonal pivoting (the algorithm of LAPACK's
/// dpstrf): each step pivots on the largest diagonal of the remaining Schur
/// complement and stops when that is at or below `cutoff`; the remainder,
/// whose diagonal is then all below the cutoff, is what is dropped. H =
/// P^T L L^T P + remainder with L n x rank in the pivoted order; order[k] is
/// the variable of pivot k.
struct PivotedCholesky {
  Eigen::MatrixXd L;
  std::vector<int> order;
};

/// Blocked as LAPACK's dpstrf: within a panel of kPanel columns each column is
/// formed left-looking from the panel's earlier columns, pivoting on `d`, the
/// remaining Schur complement's diagonal kept up to date; the trailing matrix
/// takes the panel's update as one rank-kPanel product after the panel.
PivotedCholesky PivotedCholeskyOf(const Eigen::MatrixXd& H_symmetric, double cutoff) {
  constexpr Eigen::Index kPanel = 32;
  const Eigen::Index n = H_symmetric.rows();
  Eigen::MatrixXd A = H_symmetric;  // lower triangle: L's columns so far, and the trailing matrix
  Eigen::VectorXd d = A.diagonal();
  std::vector<int> order(static_cast<size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) order[i] = static_cast<int>(i);
  Eigen::Index rank = 0;
  bool done = false;
  for (Eigen::Index panel = 0; panel < n && !done; panel += kPanel) {
    const Eigen::Index end = std::min(n, panel + kPanel);
    for (Eigen::Index k = panel; k < end; ++k, ++rank) {
      Eigen::Index j = 0;
      if (!(d.tail(n - k).maxCoeff(&j) > cutoff)) {
        done = true;
        break;
      }
      j += k;
      if (j != k) {
        SymmetricSwap(A, k, j);
        std::swap(d(k), d(j));
        std::swap(order[k], order[j]);
      }
      const double pivot = std::sqrt(d(k));
      auto column = A.col(k).tail(n - k - 1);
      column.noalias() -= A.block(k + 1, panel, n - k - 1, k - panel) * A.row(k).segment(panel, k - panel).transpose();
      column /= pivot;
      A(k, k) = pivot;
      d.tail(n - k - 1) -= column.cwiseAbs2();
    }
    const Eigen::Index width = rank - panel;
    if (!done && end < n) {
      A.bottomRightCorner(n - end, n - end).selfadjointView<Eigen::Lower>().rankUpdate(
          A.block(end, panel, n - end, width), -1.0);
    }
  }
  PivotedCholesky factor{A.leftCols(rank), std::move(order)};
  for (Eigen::Index k = 1; k < rank; ++k) factor.L.col(k).head(k).setZero();  // A's upper triangle is H's
  return factor;
}

SqrtInformation SqrtByPivotedCholesky(const Eigen::MatrixXd& H, const Eigen::VectorXd& b,
                                      const RankThreshold& threshold, bool unpivoted_first) {
  const int n = static_cast<int>(H.rows());
  if (n == 0) {
    return {Eigen::MatrixXd(0, 0), Eigen::VectorXd(0), Eigen::MatrixXd(0, 0)};
  }
  Eigen::MatrixXd H_symmetric = SymmetricPart(H);
  std::optional<SqrtInformation> cholesky;
  if (unpivoted_first) cholesky = SqrtByCholesky(H_symmetric, b, threshold);
  if (cholesky) {
    cholesky->information = std::move(H_symmetric);
    return *std::move(cholesky);
  }
  const double cutoff = EigenvalueCutoff(H_symmetric.diagonal().maxCoeff(), threshold);
  const PivotedCholesky factor = PivotedCholeskyOf(H_symmetric, cutoff);
  const Eigen::Index rank = factor.L.cols();
  // Jp = L^T P: column order[i] of Jp is row i of L; r0 = L11^-1 (P b).
  SqrtInformation sqrt{Eigen::MatrixXd(rank, n), Eigen::VectorXd(rank), Eigen::MatrixXd()};
  Eigen::VectorXd Pb(rank);
  for (Eigen::Index i = 0; i < n; ++i) {
    sqrt.sqrt_information.col(factor.order[i]) = factor.L.row(i).transpose();
    if (i < rank) Pb(i) = b(factor.order[i]);
  }
  sqrt.residual = factor.L.topRows(rank).triangularView<Eigen::Lower>().solve(Pb);
  // The remainder left out has a diagonal at or below the cutoff: positive
  // semi-definite, its Frobenius norm is at most its trace, (n - rank) times
  // the cutoff (the eigen-decomposition's square root leaves as much). One
  // that is not (H indefinite beyond round-off): the eigen-decomposition,
  // which drops exactly the weak directions, is used.
  const double dropped = 2.0 * static_cast<double>(n - rank) * cutoff;
  if (!Reproduces(sqrt.sqrt_information, H, dropped)) return SqrtByEigen(H, b, threshold);
  sqrt.information = std::move(H_symmetric);
  return sqrt;
}

/// SchurComplement through the Cholesky factor H_MM = L L^T when H_MM is
/// clearly definite: with U = H_KM L^-T, H_KK - U U^T (a symmetric rank
/// update) and b_K - U L^-1 b_M. Clearly definite: its smallest eigenvalue,
/// at least 1 / trace(H_MM^-1) = 1 / |L^-1|_F^2, is above the cutoff of its
/// largest, at most trace(H_MM); the pseudo-inverse is then the inverse. Empty
/// otherwise (the eigen-decomposition decides what is dropped).
std::optional<NormalEquations> SchurComplementByCholesky(const Eigen::MatrixXd& H, const Eigen::VectorXd& b,
                                                         int keep_dim, int marg_dim, const RankThreshold& threshold) {
  if (marg_dim == 0) return NormalEquations{SymmetricPart(H), b};
  const Eigen::MatrixXd H_MM = SymmetricPart(H.bottomRightCorner(marg_dim, marg_dim));
  const Eigen::LLT<Eigen::MatrixXd> llt(H_MM);
  if (llt.info() != Eigen::Success) return std::nullopt;
  const Eigen::MatrixXd L_inv = llt.matrixL().solve(Eigen::MatrixXd::Identity(marg_dim, marg_dim));
  if (!(1.0 / L_inv.squaredNorm() > EigenvalueCutoff(H_MM.trace(), threshold))) return std::nullopt;
  const Eigen::MatrixXd U = H.topRightCorner(keep_dim, marg_dim) * L_inv.transpose().triangularView<Eigen::Upper>();
  NormalEquations marginal{SymmetricPart(H.topLeftCorner(keep_dim, keep_dim)), Eigen::VectorXd()};
  marginal.H.selfadjointView<Eigen::Lower>().rankUpdate(U, -1.0);
  marginal.H.triangularView<Eigen::StrictlyUpper>() = marginal.H.transpose();
  marginal.b = b.head(keep_dim) - U * (L_inv * b.tail(marg_dim));
  return marginal;
}

}  // namespace

Eigen::MatrixXd PseudoInverse(const Eigen::MatrixXd& H, const RankThreshold& threshold) {
  if (!AllFinite(H) || H.rows() != H.cols()) {
    throw std::invalid_argument("PseudoInverse: expected a finite square matrix");
  }
  if (H.rows() == 3) return PseudoInverse3(H, threshold);
  const SignificantEigenpairs eig = DecomposeSignificant(H, threshold);
  return eig.eigenvectors * eig.eigenvalues.cwiseInverse().asDiagonal() *
         eig.eigenvectors.transpose();
}

void PseudoInverseInto(const Eigen::MatrixXd& H, const RankThreshold& threshold, Eigen::MatrixXd* H_inv) {
  if (H.rows() == 3 && H.cols() == 3 && H.allFinite()) {
    *H_inv = PseudoInverse3(H, threshold);
  } else {
    *H_inv = PseudoInverse(H, threshold);
  }
}

NormalEquations SchurComplement(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, int keep_dim,
                                int marg_dim, const RankThreshold& threshold) {
  RequireSizes(H, b, keep_dim, marg_dim, "SchurComplement");
  RequireFinite(H, b, "SchurComplement");
  if (std::optional<NormalEquations> marginal = SchurComplementByCholesky(H, b, keep_dim, marg_dim, threshold)) {
    return *std::move(marginal);
  }
  const Eigen::MatrixXd H_MM_inv =
      PseudoInverse(H.bottomRightCorner(marg_dim, marg_dim), threshold);
  const Eigen::MatrixXd H_KM_H_MM_inv = H.topRightCorner(keep_dim, marg_dim) * H_MM_inv;
  NormalEquations marginal;
  marginal.H = SymmetricPart(H.topLeftCorner(keep_dim, keep_dim) -
                           H_KM_H_MM_inv * H.bottomLeftCorner(marg_dim, keep_dim));
  marginal.b = b.head(keep_dim) - H_KM_H_MM_inv * b.tail(marg_dim);
  return marginal;
}

NormalEquations SchurComplementOfUncoupledBlocks(const Eigen::MatrixXd& H, const Eigen::VectorXd& b,
                                                 int keep_dim,
                                                 const std::vector<int>& marg_block_dims,
                                                 const RankThreshold& threshold) {
  int marg_dim = 0;
  for (const int dim : marg_block_dims) {
    if (dim < 0) {
      throw std::invalid_argument("SchurComplementOfUncoupledBlocks: negative block size");
    }
    marg_dim += dim;
  }
  RequireSizes(H, b, keep_dim, marg_dim, "SchurComplementOfUncoupledBlocks");
  RequireFinite(H, b, "SchurComplementOfUncoupledBlocks");
  RequireUncoupled(H, keep_dim, marg_block_dims);
  NormalEquations marginal{H.topLeftCorner(keep_dim, keep_dim), b.head(keep_dim)};
  int offset = keep_dim;
  for (const int dim : marg_block_dims) {
    EliminateBlock(H, b, offset, dim, threshold, &marginal);
    offset += dim;
  }
  marginal.H = SymmetricPart(marginal.H);
  return marginal;
}

SqrtInformation SqrtInformationFromHessian(const Eigen::MatrixXd& H, const Eigen::VectorXd& b,
                                           const RankThreshold& threshold, SqrtMethod method) {
  RequireSizes(H, b, static_cast<int>(H.rows()), 0, "SqrtInformationFromHessian");
  RequireFinite(H, b, "SqrtInformationFromHessian");
  if (method == SqrtMethod::kEigen) return SqrtByEigen(H, b, threshold);
  return SqrtByPivotedCholesky(H, b, threshold, /*unpivoted_first=*/method == SqrtMethod::kPivotedCholesky);
}

}  // namespace vio::marginalization
