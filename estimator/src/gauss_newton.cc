#include "vio/estimator/gauss_newton.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <ceres/manifold.h>
#include <glog/logging.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "vio/estimator/chain_solve.h"
#include "vio/marginalization/block_system.h"

namespace vio {
namespace {

marginalization::BlockLayout BlockLayoutOf(const GaussNewtonLayout& layout) {
  return {layout.dense, layout.eliminated, layout.residuals};
}

void ApplyStep(ceres::Problem* problem, const std::vector<double*>& blocks, const Eigen::VectorXd& dx,
               int first_col) {
  int col = first_col;
  std::vector<double> moved;
  for (double* block : blocks) {
    const int size = problem->ParameterBlockSize(block);
    const ceres::Manifold* manifold = problem->GetManifold(block);
    if (manifold == nullptr) {
      for (int k = 0; k < size; ++k) block[k] += dx[col + k];
    } else {
      moved.resize(static_cast<size_t>(size));
      CHECK(manifold->Plus(block, dx.data() + col, moved.data()));
      std::copy(moved.begin(), moved.end(), block);
    }
    col += problem->ParameterBlockTangentSize(block);
  }
}

double SquaredNorm(const ceres::Problem& problem, const std::vector<double*>& blocks) {
  double sum = 0;
  for (const double* block : blocks) {
    for (int k = 0; k < problem.ParameterBlockSize(block); ++k) sum += block[k] * block[k];
  }
  return sum;
}

/// Solves H dx = -b for H symmetric positive definite, given by its upper
/// triangle (semi-definite falls back to LDLT), factored by panels in
/// `factor` (FactorLowerInPlace, memory kept between solves). False when no
/// finite solution exists.
bool SolveDense(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, Eigen::MatrixXd* factor, Eigen::VectorXd* dx) {
  if (H.rows() == 0) {
    dx->resize(0);
    return true;
  }
  factor->resize(H.rows(), H.cols());
  factor->triangularView<Eigen::Lower>() = H.transpose();
  if (FactorLowerInPlace(*factor)) {
    *dx = -b;
    factor->triangularView<Eigen::Lower>().solveInPlace(*dx);
    factor->transpose().triangularView<Eigen::Upper>().solveInPlace(*dx);
  } else {
    *dx = Eigen::LDLT<Eigen::MatrixXd, Eigen::Upper>(H).solve(-b);
  }
  return dx->allFinite();
}

}  // namespace

// The layout's normal equations (marginalization::BlockSystem, the assembly
// the marginalization uses too), the chain of speed/bias blocks when its band
// is narrow, and the values before the last step.
struct GaussNewtonSolver::System {
  ceres::Problem* problem;
  GaussNewtonLayout layout;
  marginalization::BlockSystem equations;
  std::vector<ChainBlock> chain;  ///< empty: solve densely
  int chain_bandwidth = 0;
  ChainSolver chain_solver;
  /// The layout's values before the last step, dense then eliminated blocks.
  std::vector<double> before_step;
  Eigen::MatrixXd dense_factor;  ///< SolveDense's factor, kept between steps

  System(ceres::Problem* p, GaussNewtonLayout l)
      : problem(p), layout(std::move(l)), equations(p, BlockLayoutOf(layout)) {
    FindChain();
  }

  void Relayout(GaussNewtonLayout l) {
    layout = std::move(l);
    equations.Relayout(BlockLayoutOf(layout));
    FindChain();
    before_step.clear();
  }

  // The chain's bandwidth: the widest gap in chain order between two chain
  // blocks that one residual, or one eliminated block's Schur update, couples.
  // Used when the band is narrow enough to beat the dense solve.
  void FindChain() {
    chain.clear();
    std::vector<int> position(layout.dense.size(), -1);
    for (size_t k = 0; k < layout.chain.size(); ++k) position[layout.chain[k]] = static_cast<int>(k);
    chain_bandwidth = equations.CouplingBandwidth(position);
    const int m = static_cast<int>(layout.chain.size());
    if (m < 2 || 4 * (chain_bandwidth + 1) > m) return;
    // Each chain block's span over the rest (the columns the chain solver
    // reads its coupling from): a speed/bias block's two poses, not every
    // column up to its neighbour's.
    std::vector<bool> rest(layout.dense.size(), true);
    for (const int d : layout.chain) rest[static_cast<size_t>(d)] = false;
    const std::vector<std::pair<int, int>> spans = equations.CoupledSpans(rest);
    for (const int d : layout.chain) {
      const auto [first, last] = spans[static_cast<size_t>(d)];
      chain.push_back({equations.dense_offset(d), equations.dense_size(d), equations.dense_offset(first),
                       equations.dense_offset(last) + equations.dense_size(last)});
    }
  }

  // The reduced system (H upper triangle, b) at the current values; false
  // when the layout is empty or evaluation fails.
  bool Reduce(double* cost) {
    if (layout.residuals.empty() || (layout.dense.empty() && layout.eliminated.empty())) return false;
    return equations.Reduce(cost);
  }

  void SaveValues() {
    before_step.clear();
    for (const std::vector<double*>* blocks : {&layout.dense, &layout.eliminated}) {
      for (const double* block : *blocks) {
        before_step.insert(before_step.end(), block, block + problem->ParameterBlockSize(block));
      }
    }
  }

  void RestoreValues() const {
    CHECK(!before_step.empty()) << "UndoStep without a step";
    auto value = before_step.begin();
    for (const std::vector<double*>* blocks : {&layout.dense, &layout.eliminated}) {
      for (double* block : *blocks) {
        const int size = problem->ParameterBlockSize(block);
        std::copy(value, value + size, block);
        value += size;
      }
    }
  }

  GaussNewtonStep Step() {
    GaussNewtonStep step;
    if (!Reduce(&step.cost)) return step;
    const Eigen::MatrixXd& H = equations.H();
    const Eigen::VectorXd& b = equations.b();
    Eigen::VectorXd dx_dense;
    const bool chained = !chain.empty() && chain_solver.Solve(H, b, chain, chain_bandwidth, &dx_dense);
    if (!chained && !SolveDense(H, b, &dense_factor, &dx_dense)) return step;
    Eigen::VectorXd dx;
    equations.BackSubstitute(dx_dense, &dx);
    if (!dx.allFinite()) return step;
    step.values_norm = std::sqrt(SquaredNorm(*problem, layout.dense) + SquaredNorm(*problem, layout.eliminated));
    step.step_norm = dx.norm();
    SaveValues();
    ApplyStep(problem, layout.dense, dx, 0);
    ApplyStep(problem, layout.eliminated, dx, equations.dense_dim());
    step.ok = true;
    return step;
  }
};

GaussNewtonSolver::GaussNewtonSolver(ceres::Problem* problem, GaussNewtonLayout layout)
    : system_(std::make_unique<System>(problem, std::move(layout))) {}

GaussNewtonSolver::~GaussNewtonSolver() = default;

void GaussNewtonSolver::Relayout(GaussNewtonLayout layout) { system_->Relayout(std::move(layout)); }

GaussNewtonStep GaussNewtonSolver::Step() { return system_->Step(); }

void GaussNewtonSolver::UndoStep() { system_->RestoreValues(); }

bool GaussNewtonSolver::Cost(double* cost) { return system_->equations.Cost(cost); }

bool GaussNewtonSolver::Reduce(ReducedSystem* system) {
  double cost = 0;
  if (!system_->Reduce(&cost)) return false;
  system->H = system_->equations.H();
  system->H.triangularView<Eigen::StrictlyLower>() = system->H.transpose();
  system->b = system_->equations.b();
  return true;
}

bool ReducedNormalEquations(ceres::Problem* problem, const GaussNewtonLayout& layout, ReducedSystem* system) {
  return GaussNewtonSolver(problem, layout).Reduce(system);
}

GaussNewtonStep TakeGaussNewtonStep(ceres::Problem* problem, const GaussNewtonLayout& layout) {
  return GaussNewtonSolver(problem, layout).Step();
}

bool EvaluateCost(ceres::Problem* problem, const GaussNewtonLayout& layout, double* cost) {
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.residual_blocks = layout.residuals;
  *cost = 0;
  return layout.residuals.empty() || problem->Evaluate(evaluate, cost, nullptr, nullptr, nullptr);
}

}  // namespace vio
