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

/// A layout block's sizes and manifold, looked up in the problem once per layout.
struct BlockShape {
  double* values = nullptr;
  int size = 0;     ///< ambient
  int tangent = 0;
  const ceres::Manifold* manifold = nullptr;
};

std::vector<BlockShape> ShapesOf(const ceres::Problem& problem, const std::vector<double*>& dense,
                                 const std::vector<double*>& eliminated) {
  std::vector<BlockShape> shapes;
  shapes.reserve(dense.size() + eliminated.size());
  for (const std::vector<double*>* blocks : {&dense, &eliminated}) {
    for (double* block : *blocks) {
      shapes.push_back({block, problem.ParameterBlockSize(block), problem.ParameterBlockTangentSize(block),
                        problem.GetManifold(block)});
    }
  }
  return shapes;
}

// x <- x ⊞ dx over the blocks, dense then eliminated (dx's column order).
void ApplyStep(const std::vector<BlockShape>& shapes, const Eigen::VectorXd& dx) {
  int col = 0;
  std::vector<double> moved;
  for (const BlockShape& shape : shapes) {
    double* block = shape.values;
    if (shape.manifold == nullptr) {
      for (int k = 0; k < shape.size; ++k) block[k] += dx[col + k];
    } else {
      moved.resize(static_cast<size_t>(shape.size));
      CHECK(shape.manifold->Plus(block, dx.data() + col, moved.data()));
      std::copy(moved.begin(), moved.end(), block);
    }
    col += shape.tangent;
  }
}

// The squared norm of shapes [first, last)'s values.
double SquaredNorm(const std::vector<BlockShape>& shapes, size_t first, size_t last) {
  double sum = 0;
  for (size_t b = first; b < last; ++b) {
    for (int k = 0; k < shapes[b].size; ++k) sum += shapes[b].values[k] * shapes[b].values[k];
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
  /// The layout's blocks, dense then eliminated (the columns' order).
  std::vector<BlockShape> shapes;

  System(ceres::Problem* p, GaussNewtonLayout l)
      : problem(p), layout(std::move(l)), equations(p, BlockLayoutOf(layout)) {
    FindChain();
    shapes = ShapesOf(*problem, layout.dense, layout.eliminated);
  }

  void Relayout(GaussNewtonLayout l) {
    layout = std::move(l);
    equations.Relayout(BlockLayoutOf(layout));
    FindChain();
    shapes = ShapesOf(*problem, layout.dense, layout.eliminated);
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
    for (const BlockShape& shape : shapes) before_step.insert(before_step.end(), shape.values, shape.values + shape.size);
  }

  void RestoreValues() const {
    CHECK(!before_step.empty()) << "UndoStep without a step";
    auto value = before_step.begin();
    for (const BlockShape& shape : shapes) {
      std::copy(value, value + shape.size, shape.values);
      value += shape.size;
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
    const size_t dense = layout.dense.size();
    step.values_norm = std::sqrt(SquaredNorm(shapes, 0, dense) + SquaredNorm(shapes, dense, shapes.size()));
    step.step_norm = dx.norm();
    SaveValues();
    ApplyStep(shapes, dx);
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
