// The window's Gauss-Newton step is the theory's: on a nonlinear
// visual-inertial window (poses off the truth, so residuals are large and the
// cost is far from quadratic), one step of Window::TakeSteps(1) equals the
// closed-form step dx = -(J^T J)^-1 J^T r of the whole cost, with J and r
// evaluated independently (every block, Ceres' own column order, dense QR),
// applied through each block's manifold. LM's first step is not that step.
#include <map>
#include <vector>

#include <ceres/crs_matrix.h>
#include <gtest/gtest.h>

#include <Eigen/QR>

#include "estimator_test_support.h"
#include "synthetic_window.h"
#include "vio/estimator/window.h"

namespace vio {
namespace {

constexpr int kFrames = 10;
constexpr int kFirst = 60;
constexpr double kOffsetM = 0.01;  // positions off the truth, alternating

ModelOptions Model() {
  ModelOptions model;
  model.huber_px = 0;  // the plain least-squares cost: J^T J is its Gauss-Newton Hessian
  return model;
}

const test::SyntheticFlight& Flight() {
  static const test::SyntheticFlight flight(6.0, 7);
  return flight;
}

/// Every parameter block's values, keyed by address (stable within a window).
std::map<const double*, std::vector<double>> Values(ceres::Problem& problem) {
  std::vector<double*> blocks;
  problem.GetParameterBlocks(&blocks);
  std::map<const double*, std::vector<double>> values;
  for (double* b : blocks) values[b].assign(b, b + problem.ParameterBlockSize(b));
  return values;
}

/// x ⊞ dx of the closed-form Gauss-Newton step of the whole problem.
std::map<const double*, std::vector<double>> ClosedFormStep(ceres::Problem& problem) {
  std::vector<double*> blocks;
  problem.GetParameterBlocks(&blocks);
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks = blocks;
  double cost = 0;
  std::vector<double> r;
  ceres::CRSMatrix crs;
  EXPECT_TRUE(problem.Evaluate(evaluate, &cost, &r, nullptr, &crs));
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int i = 0; i < crs.num_rows; ++i) {
    for (int a = crs.rows[i]; a < crs.rows[i + 1]; ++a) J(i, crs.cols[a]) = crs.values[a];
  }
  const Eigen::VectorXd residual = Eigen::Map<const Eigen::VectorXd>(r.data(), static_cast<Eigen::Index>(r.size()));
  const Eigen::VectorXd dx = J.colPivHouseholderQr().solve(-residual);
  std::map<const double*, std::vector<double>> after;
  int col = 0;
  for (double* b : blocks) {
    const int size = problem.ParameterBlockSize(b);
    std::vector<double> x(b, b + size);
    std::vector<double> moved = test::BlockPlus(problem.GetManifold(b), x,
                                                dx.segment(col, problem.ParameterBlockTangentSize(b)));
    after[b] = moved;
    col += problem.ParameterBlockTangentSize(b);
  }
  return after;
}

double LargestDifference(const std::map<const double*, std::vector<double>>& a,
                         const std::map<const double*, std::vector<double>>& b) {
  double largest = 0;
  for (const auto& [block, values] : a) {
    for (size_t k = 0; k < values.size(); ++k) largest = std::max(largest, std::abs(values[k] - b.at(block)[k]));
  }
  return largest;
}

TEST(WindowGaussNewton, OneStepEqualsTheClosedFormStepOnANonlinearWindow) {
  Window window(Model(), Flight().stereo());
  Flight().Build(window, Model(), kFirst, kFrames, kOffsetM);
  const auto before = Values(window.problem());
  const auto expected = ClosedFormStep(window.problem());
  // The step is large: the window is far from its optimum.
  ASSERT_GT(LargestDifference(expected, before), 0.1);

  SolverOptions gn;
  gn.step = "gn";
  const SolveReport report = window.TakeSteps(1, gn);
  ASSERT_TRUE(report.usable);
  EXPECT_EQ(report.iterations, 1);
  EXPECT_LT(report.final_cost, report.initial_cost);
  EXPECT_LE(LargestDifference(Values(window.problem()), expected), 1e-10);
}

TEST(WindowGaussNewton, OneLevenbergMarquardtStepIsNotTheGaussNewtonStep) {
  Window window(Model(), Flight().stereo());
  Flight().Build(window, Model(), kFirst, kFrames, kOffsetM);
  const auto before = Values(window.problem());
  const auto expected = ClosedFormStep(window.problem());
  SolverOptions lm;
  lm.step = "lm";
  window.TakeSteps(1, lm);
  EXPECT_GT(LargestDifference(Values(window.problem()), expected), 1e-3 * LargestDifference(expected, before));
}

TEST(WindowGaussNewton, SolveStopsByTheConvergenceCriterionNotTheCap) {
  Window window(Model(), Flight().stereo());
  Flight().Build(window, Model(), kFirst, kFrames, kOffsetM);
  SolverOptions gn;
  gn.max_iterations = 50;
  gn.function_tolerance = 1e-10;
  const SolveReport report = window.Solve(gn);
  EXPECT_TRUE(report.converged);
  EXPECT_GE(report.iterations, 2);
  EXPECT_LT(report.iterations, gn.max_iterations);
  // At the optimum a further step does not lower the cost.
  const SolveReport further = window.TakeSteps(1, gn);
  EXPECT_GE(further.final_cost, further.initial_cost * (1 - 1e-9));
}

}  // namespace
}  // namespace vio
