#include "vio/estimator/gauss_newton.h"

#include <algorithm>
#include <cmath>

#include <ceres/crs_matrix.h>
#include <ceres/manifold.h>
#include <glog/logging.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "vio/marginalization/linear_algebra.h"

namespace vio {
namespace {

// A row of J with more nonzeros than this (a marginalization prior spanning
// its blanket) is gathered into a dense matrix whose product Eigen blocks.
constexpr int kDenseRow = 64;

/// One eliminated block: its rows of J and its part of the normal equations.
struct EliminatedBlock {
  int offset = 0;               ///< first column
  int size = 0;                 ///< tangent size
  std::vector<int> rows;        ///< rows of J touching it
  std::vector<int> dense_cols;  ///< dense columns those rows touch, ascending
  Eigen::MatrixXd H;            ///< J_e^T J_e
  Eigen::VectorXd b;            ///< J_e^T r
  Eigen::MatrixXd W;            ///< J_d^T J_e on dense_cols
  Eigen::MatrixXd H_inv;        ///< (pseudo-)inverse of H
};

int TangentSize(const ceres::Problem& problem, const double* block) {
  return problem.ParameterBlockTangentSize(block);
}

/// Normal equations of the dense columns and the per-block parts of the
/// eliminated ones, summed in row order.
class NormalEquationsBuilder {
 public:
  NormalEquationsBuilder(const ceres::CRSMatrix& J, const std::vector<double>& r, int dense_dim,
                         std::vector<EliminatedBlock>* blocks)
      : J_(J), r_(r), dense_dim_(dense_dim), blocks_(*blocks),
        H_(Eigen::MatrixXd::Zero(dense_dim, dense_dim)), b_(Eigen::VectorXd::Zero(dense_dim)) {}

  void Build() {
    for (int i = 0; i < J_.num_rows; ++i) {
      const int e = EliminatedBlockOf(i);
      if (e >= 0) blocks_[e].rows.push_back(i);
      AddDenseRow(i);
    }
    AddGatheredDenseRows();
    for (EliminatedBlock& block : blocks_) AddEliminatedBlock(block);
  }

  Eigen::MatrixXd& H() { return H_; }
  Eigen::VectorXd& b() { return b_; }

 private:
  // The eliminated block a row touches, -1 for none; two would couple them.
  int EliminatedBlockOf(int i) const {
    int found = -1;
    for (int a = J_.rows[i]; a < J_.rows[i + 1]; ++a) {
      if (J_.cols[a] < dense_dim_) continue;
      const auto it = std::upper_bound(blocks_.begin(), blocks_.end(), J_.cols[a],
                                       [](int col, const EliminatedBlock& b) { return col < b.offset; });
      const int e = static_cast<int>(it - blocks_.begin()) - 1;
      CHECK(found < 0 || found == e) << "a residual couples two eliminated blocks";
      found = e;
    }
    return found;
  }

  void AddDenseRow(int i) {
    const int begin = J_.rows[i], end = J_.rows[i + 1];
    if (end - begin > kDenseRow) {
      gathered_.push_back(i);
      return;
    }
    for (int a = begin; a < end; ++a) {
      if (J_.cols[a] >= dense_dim_) continue;
      b_[J_.cols[a]] += J_.values[a] * r_[i];
      for (int c = begin; c < end; ++c) {
        if (J_.cols[c] < dense_dim_) H_(J_.cols[a], J_.cols[c]) += J_.values[a] * J_.values[c];
      }
    }
  }

  void AddGatheredDenseRows() {
    if (gathered_.empty()) return;
    Eigen::MatrixXd Jd = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(gathered_.size()), dense_dim_);
    Eigen::VectorXd rd(Jd.rows());
    for (Eigen::Index k = 0; k < Jd.rows(); ++k) {
      const int i = gathered_[k];
      for (int a = J_.rows[i]; a < J_.rows[i + 1]; ++a) {
        CHECK_LT(J_.cols[a], dense_dim_) << "a dense row touches an eliminated block";
        Jd(k, J_.cols[a]) = J_.values[a];
      }
      rd[k] = r_[i];
    }
    H_.noalias() += Jd.transpose() * Jd;
    b_.noalias() += Jd.transpose() * rd;
  }

  void AddEliminatedBlock(EliminatedBlock& block) const {
    for (int i : block.rows) {
      for (int a = J_.rows[i]; a < J_.rows[i + 1]; ++a) {
        if (J_.cols[a] < dense_dim_) block.dense_cols.push_back(J_.cols[a]);
      }
    }
    std::sort(block.dense_cols.begin(), block.dense_cols.end());
    block.dense_cols.erase(std::unique(block.dense_cols.begin(), block.dense_cols.end()), block.dense_cols.end());
    const auto local = [&block](int col) {
      return static_cast<int>(std::lower_bound(block.dense_cols.begin(), block.dense_cols.end(), col) -
                              block.dense_cols.begin());
    };
    block.H = Eigen::MatrixXd::Zero(block.size, block.size);
    block.b = Eigen::VectorXd::Zero(block.size);
    block.W = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(block.dense_cols.size()), block.size);
    for (int i : block.rows) {
      for (int a = J_.rows[i]; a < J_.rows[i + 1]; ++a) {
        if (J_.cols[a] < dense_dim_) continue;
        const int ea = J_.cols[a] - block.offset;
        block.b[ea] += J_.values[a] * r_[i];
        for (int c = J_.rows[i]; c < J_.rows[i + 1]; ++c) {
          if (J_.cols[c] >= dense_dim_) {
            block.H(ea, J_.cols[c] - block.offset) += J_.values[a] * J_.values[c];
          } else {
            block.W(local(J_.cols[c]), ea) += J_.values[c] * J_.values[a];
          }
        }
      }
    }
  }

  const ceres::CRSMatrix& J_;
  const std::vector<double>& r_;
  const int dense_dim_;
  std::vector<EliminatedBlock>& blocks_;
  Eigen::MatrixXd H_;
  Eigen::VectorXd b_;
  std::vector<int> gathered_;
};

/// Schur complement of the eliminated blocks into (H, b), block by block.
void EliminateBlocks(std::vector<EliminatedBlock>& blocks, Eigen::MatrixXd& H, Eigen::VectorXd& b) {
  for (EliminatedBlock& block : blocks) {
    block.H_inv = marginalization::PseudoInverse(block.H);
    const Eigen::MatrixXd WH_inv = block.W * block.H_inv;
    const Eigen::MatrixXd update = WH_inv * block.W.transpose();
    const Eigen::VectorXd b_update = WH_inv * block.b;
    const int m = static_cast<int>(block.dense_cols.size());
    for (int p = 0; p < m; ++p) {
      b[block.dense_cols[p]] -= b_update[p];
      for (int q = 0; q < m; ++q) H(block.dense_cols[p], block.dense_cols[q]) -= update(p, q);
    }
  }
}

/// Solves H dx = -b (H symmetric positive definite; semi-definite falls back
/// to LDLT). False when no finite solution exists.
bool SolveDense(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, Eigen::VectorXd* dx) {
  if (H.rows() == 0) {
    dx->resize(0);
    return true;
  }
  Eigen::LLT<Eigen::MatrixXd> llt(H);
  if (llt.info() == Eigen::Success) {
    *dx = llt.solve(-b);
  } else {
    *dx = H.ldlt().solve(-b);
  }
  return dx->allFinite();
}

void ApplyStep(ceres::Problem* problem, const std::vector<double*>& blocks, const Eigen::VectorXd& dx,
               int first_col) {
  int col = first_col;
  std::vector<double> moved;
  for (double* block : blocks) {
    const int size = problem->ParameterBlockSize(block);
    const int tangent = TangentSize(*problem, block);
    const ceres::Manifold* manifold = problem->GetManifold(block);
    if (manifold == nullptr) {
      for (int k = 0; k < size; ++k) block[k] += dx[col + k];
    } else {
      moved.resize(static_cast<size_t>(size));
      CHECK(manifold->Plus(block, dx.data() + col, moved.data()));
      std::copy(moved.begin(), moved.end(), block);
    }
    col += tangent;
  }
}

double SquaredNorm(const ceres::Problem& problem, const std::vector<double*>& blocks) {
  double sum = 0;
  for (const double* block : blocks) {
    for (int k = 0; k < problem.ParameterBlockSize(block); ++k) sum += block[k] * block[k];
  }
  return sum;
}

/// The linearized system at the current values with the eliminated blocks
/// Schur-complemented out: H dx_dense = -b over the dense columns.
struct Linearization {
  double cost = 0;
  int dense_dim = 0;
  int num_cols = 0;
  std::vector<double*> parameter_blocks;  ///< dense, then eliminated
  std::vector<EliminatedBlock> blocks;
  Eigen::MatrixXd H;
  Eigen::VectorXd b;
};

bool Linearize(ceres::Problem* problem, const GaussNewtonLayout& layout, Linearization* out) {
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.residual_blocks = layout.residuals;
  evaluate.parameter_blocks = layout.dense;
  evaluate.parameter_blocks.insert(evaluate.parameter_blocks.end(), layout.eliminated.begin(),
                                   layout.eliminated.end());
  // An empty list would mean every block.
  if (evaluate.parameter_blocks.empty() || evaluate.residual_blocks.empty()) return false;
  std::vector<double> r;
  ceres::CRSMatrix J;
  if (!problem->Evaluate(evaluate, &out->cost, &r, nullptr, &J)) return false;

  out->parameter_blocks = evaluate.parameter_blocks;
  out->num_cols = J.num_cols;
  out->dense_dim = 0;
  for (const double* block : layout.dense) out->dense_dim += TangentSize(*problem, block);
  out->blocks.assign(layout.eliminated.size(), EliminatedBlock());
  int col = out->dense_dim;
  for (size_t k = 0; k < out->blocks.size(); ++k) {
    out->blocks[k].offset = col;
    out->blocks[k].size = TangentSize(*problem, layout.eliminated[k]);
    col += out->blocks[k].size;
  }
  NormalEquationsBuilder builder(J, r, out->dense_dim, &out->blocks);
  builder.Build();
  EliminateBlocks(out->blocks, builder.H(), builder.b());
  out->H = std::move(builder.H());
  out->b = std::move(builder.b());
  return true;
}

}  // namespace

bool ReducedNormalEquations(ceres::Problem* problem, const GaussNewtonLayout& layout, ReducedSystem* system) {
  Linearization linearization;
  if (!Linearize(problem, layout, &linearization)) return false;
  system->H = std::move(linearization.H);
  system->b = std::move(linearization.b);
  return true;
}

GaussNewtonStep TakeGaussNewtonStep(ceres::Problem* problem, const GaussNewtonLayout& layout) {
  GaussNewtonStep step;
  Linearization lin;
  if (!Linearize(problem, layout, &lin)) return step;
  step.cost = lin.cost;

  Eigen::VectorXd dx = Eigen::VectorXd::Zero(lin.num_cols);
  Eigen::VectorXd dx_dense;
  if (!SolveDense(lin.H, lin.b, &dx_dense)) return step;
  dx.head(lin.dense_dim) = dx_dense;
  for (const EliminatedBlock& block : lin.blocks) {
    Eigen::VectorXd rhs = block.b;
    for (size_t p = 0; p < block.dense_cols.size(); ++p) {
      rhs += block.W.row(static_cast<Eigen::Index>(p)).transpose() * dx_dense[block.dense_cols[p]];
    }
    dx.segment(block.offset, block.size) = -block.H_inv * rhs;
  }
  if (!dx.allFinite()) return step;

  step.values_norm = std::sqrt(SquaredNorm(*problem, lin.parameter_blocks));
  step.step_norm = dx.norm();
  ApplyStep(problem, layout.dense, dx, 0);
  ApplyStep(problem, layout.eliminated, dx, lin.dense_dim);
  step.ok = true;
  return step;
}

bool EvaluateCost(ceres::Problem* problem, const GaussNewtonLayout& layout, double* cost) {
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.residual_blocks = layout.residuals;
  *cost = 0;
  return layout.residuals.empty() || problem->Evaluate(evaluate, cost, nullptr, nullptr, nullptr);
}

}  // namespace vio
