#include "vio/marginalization/linear_algebra.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <glog/logging.h>

namespace vio::marginalization {
namespace {

// Largest relative error ||Jp^T Jp - H||_F / ||H||_F the pivoted LDLT square root may leave.
constexpr double kReconstructionTolerance = 1e-13;

/// The eigen-pairs of a symmetric PSD matrix whose eigenvalue survives the
/// threshold: H ~= eigenvectors * diag(eigenvalues) * eigenvectors^T.
struct SignificantEigenpairs {
  Eigen::VectorXd eigenvalues;   ///< r, all > threshold
  Eigen::MatrixXd eigenvectors;  ///< n x r, orthonormal columns
};

void RequireFinite(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, const char* where) {
  if (!H.allFinite() || !b.allFinite()) {
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
/// fixed-size matrices, without heap allocation: the same decomposition and
/// cutoff as DecomposeSignificant.
Eigen::Matrix3d PseudoInverse3(const Eigen::Matrix3d& H, const RankThreshold& threshold) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(0.5 * (H + H.transpose()));
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

SqrtInformation SqrtByEigen(const Eigen::MatrixXd& H, const Eigen::VectorXd& b,
                            const RankThreshold& threshold) {
  const SignificantEigenpairs eig = DecomposeSignificant(H, threshold);
  const Eigen::MatrixXd V_transpose = eig.eigenvectors.transpose();
  const Eigen::VectorXd sqrt_lambda = eig.eigenvalues.cwiseSqrt();
  return {sqrt_lambda.asDiagonal() * V_transpose,
          sqrt_lambda.cwiseInverse().asDiagonal() * (V_transpose * b)};
}

SqrtInformation SqrtByPivotedLdlt(const Eigen::MatrixXd& H, const Eigen::VectorXd& b,
                                  const RankThreshold& threshold) {
  const int n = static_cast<int>(H.rows());
  if (n == 0) {
    return {Eigen::MatrixXd(0, 0), Eigen::VectorXd(0)};
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(SymmetricPart(H));
  if (ldlt.info() != Eigen::Success) {  // a zero pivot with a non-zero column: not PSD
    return SqrtByEigen(H, b, threshold);
  }
  const Eigen::VectorXd D = ldlt.vectorD();
  const double cutoff = EigenvalueCutoff(D.maxCoeff(), threshold);
  std::vector<int> kept;
  for (int i = 0; i < n; ++i) {
    if (D(i) > cutoff) {
      kept.push_back(i);
    }
  }
  const Eigen::MatrixXd Lt_P =
      (ldlt.transpositionsP().transpose() * Eigen::MatrixXd(ldlt.matrixL())).transpose();
  const Eigen::VectorXd Linv_P_b = ldlt.matrixL().solve(ldlt.transpositionsP() * b);
  const Eigen::VectorXd sqrt_D = D(kept).cwiseSqrt();
  SqrtInformation sqrt{sqrt_D.asDiagonal() * Lt_P(kept, Eigen::all),
                       sqrt_D.cwiseInverse().asDiagonal() * Linv_P_b(kept)};
  // On a rank-deficient H (marginalized features leave one) a pivot at the
  // round-off level can come before larger ones, and the pivots after it are
  // amplified round-off: then the factor does not give H back, and the
  // eigen-decomposition, which drops exactly the weak directions, is used.
  const double reconstruction = (sqrt.sqrt_information.transpose() * sqrt.sqrt_information - H).norm();
  if (!(reconstruction <= kReconstructionTolerance * H.norm())) return SqrtByEigen(H, b, threshold);
  return sqrt;
}

}  // namespace

Eigen::MatrixXd PseudoInverse(const Eigen::MatrixXd& H, const RankThreshold& threshold) {
  if (!H.allFinite() || H.rows() != H.cols()) {
    throw std::invalid_argument("PseudoInverse: expected a finite square matrix");
  }
  if (H.rows() == 3) return PseudoInverse3(H, threshold);
  const SignificantEigenpairs eig = DecomposeSignificant(H, threshold);
  return eig.eigenvectors * eig.eigenvalues.cwiseInverse().asDiagonal() *
         eig.eigenvectors.transpose();
}

NormalEquations SchurComplement(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, int keep_dim,
                                int marg_dim, const RankThreshold& threshold) {
  RequireSizes(H, b, keep_dim, marg_dim, "SchurComplement");
  RequireFinite(H, b, "SchurComplement");
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
  return method == SqrtMethod::kEigen ? SqrtByEigen(H, b, threshold)
                                      : SqrtByPivotedLdlt(H, b, threshold);
}

}  // namespace vio::marginalization
