// The optimization framework's two steps on a whitened linearized cost
// (design paper, Algorithms 1 and 2), over the marginalization library's
// dense linear algebra.
#include <Eigen/Cholesky>
#include <numeric>

#include "equivalence_internal.h"
#include "vio/marginalization/equivalence.h"
#include "vio/marginalization/linear_algebra.h"

namespace vio::marginalization {
namespace {

using internal::Symmetrized;

/// (H^-1, -H^-1 b) of a positive definite information matrix.
struct InverseAndStep {
  Eigen::MatrixXd covariance;
  Eigen::VectorXd step;
};

InverseAndStep InvertInformation(const Eigen::MatrixXd& H, const Eigen::VectorXd& b) {
  const Eigen::LLT<Eigen::MatrixXd> llt(Symmetrized(H));
  VIO_REQUIRE_INPUT(llt.info() == Eigen::Success);  // the cost has full column rank
  return {Symmetrized(llt.solve(Eigen::MatrixXd::Identity(H.rows(), H.cols()))), -llt.solve(b)};
}

}  // namespace

LinearizedCost Whiten(const std::vector<ResidualTerm>& terms) {
  VIO_REQUIRE_INPUT(!terms.empty());
  const Eigen::Index cols = terms.front().J.cols();
  Eigen::Index rows = 0;
  for (const ResidualTerm& term : terms) rows += term.r.size();
  LinearizedCost cost{Eigen::MatrixXd(rows, cols), Eigen::VectorXd(rows)};
  Eigen::Index row = 0;
  for (const ResidualTerm& term : terms) {
    const Eigen::Index m = term.r.size();
    VIO_REQUIRE_SHAPE(term.J, m, cols);
    VIO_REQUIRE_SHAPE(term.Sigma, m, m);
    const Eigen::LLT<Eigen::MatrixXd> llt(term.Sigma);  // Σ = L L^T, Σ^-1/2 := L^-1
    VIO_REQUIRE_INPUT(llt.info() == Eigen::Success);
    cost.J.middleRows(row, m) = llt.matrixL().solve(term.J);
    cost.C.segment(row, m) = llt.matrixL().solve(term.r);
    row += m;
  }
  return cost;
}

// Algorithm 1: Σ_t = (J^T J)^-1, μ_t = ξ* ⊞ (-(J^T J)^-1 J^T C(ξ*)).
Gaussian GaussNewtonStep(const LinearizedCost& cost, const Eigen::VectorXd& linearization_point,
                         const StateLayout& layout) {
  VIO_REQUIRE_SHAPE(cost.J, cost.C.size(), layout.TangentSize());
  const InverseAndStep solution = InvertInformation(cost.J.transpose() * cost.J, cost.J.transpose() * cost.C);
  return {layout.Plus(linearization_point, solution.step), solution.covariance};
}

// Algorithm 2: the Schur complement of H = J^T J, b = J^T C is
// (J_K^T P J_K, J_K^T P C) with P = I - J_M (J_M^T J_M)^-1 J_M^T, so
// Σ_K = H*^-1 and μ_K = ξ_K* - Σ_K J_K^T P C (eqs. 2.5, 2.6).
Gaussian MarginalizationStep(const LinearizedCost& cost, const Eigen::VectorXd& kept_linearization_point,
                             const StateLayout& kept_layout,
                             const std::vector<int>& marginalized_block_dims) {
  const int keep_dim = kept_layout.TangentSize();
  const int marg_dim = std::accumulate(marginalized_block_dims.begin(), marginalized_block_dims.end(), 0);
  VIO_REQUIRE_SHAPE(cost.J, cost.C.size(), keep_dim + marg_dim);
  const Eigen::MatrixXd H = cost.J.transpose() * cost.J;
  const Eigen::VectorXd b = cost.J.transpose() * cost.C;
  const NormalEquations marginal =
      marginalized_block_dims.size() == 1
          ? SchurComplement(H, b, keep_dim, marg_dim)
          : SchurComplementOfUncoupledBlocks(H, b, keep_dim, marginalized_block_dims);
  const InverseAndStep solution = InvertInformation(marginal.H, marginal.b);
  return {kept_layout.Plus(kept_linearization_point, solution.step), solution.covariance};
}

}  // namespace vio::marginalization
