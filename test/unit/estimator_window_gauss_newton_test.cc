// The window's Gauss-Newton step is the theory's: on a nonlinear
// visual-inertial window (poses off the truth, so residuals are large and the
// cost is far from quadratic), one step of Window::TakeSteps(1) equals the
// closed-form step dx = -(J^T J)^-1 J^T r of the whole cost, with J and r
// evaluated independently (every block, Ceres' own column order, dense QR),
// applied through each block's manifold. LM's first step is not that step.
#include <cmath>
#include <limits>
#include <map>
#include <tuple>
#include <vector>

#include <ceres/crs_matrix.h>
#include <ceres/sized_cost_function.h>
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/QR>

#include "estimator_test_support.h"
#include "synthetic_window.h"
#include "vio/estimator/gauss_newton.h"
#include "vio/estimator/stereo_factor.h"
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

/// J (dense, from Ceres' CRS Jacobian) and r of `evaluate`'s blocks.
void EvaluateDense(ceres::Problem& problem, const ceres::Problem::EvaluateOptions& evaluate, Eigen::MatrixXd* J,
                   Eigen::VectorXd* residual) {
  double cost = 0;
  std::vector<double> r;
  ceres::CRSMatrix crs;
  ASSERT_TRUE(problem.Evaluate(evaluate, &cost, &r, nullptr, &crs));
  *J = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int i = 0; i < crs.num_rows; ++i) {
    for (int a = crs.rows[i]; a < crs.rows[i + 1]; ++a) (*J)(i, crs.cols[a]) = crs.values[a];
  }
  *residual = Eigen::Map<const Eigen::VectorXd>(r.data(), static_cast<Eigen::Index>(r.size()));
}

/// x ⊞ dx of the closed-form Gauss-Newton step of the whole problem.
std::map<const double*, std::vector<double>> ClosedFormStep(ceres::Problem& problem) {
  std::vector<double*> blocks;
  problem.GetParameterBlocks(&blocks);
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks = blocks;
  Eigen::MatrixXd J;
  Eigen::VectorXd residual;
  EvaluateDense(problem, evaluate, &J, &residual);
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

// The step assembles a marginalization prior from its information Jp^T Jp and
// the local-coordinate Jacobians T: after a step moved every block off the
// prior's linearization point (T != I), the next step is still the closed form.
TEST(WindowGaussNewton, OneStepWithAMarginalizationPriorOffItsLinearizationPointEqualsTheClosedFormStep) {
  Window window(Model(), Flight().stereo());
  Flight().Build(window, Model(), kFirst, kFrames, kOffsetM);
  window.Marginalize({window.states().begin()->first}, {});
  SolverOptions gn;
  gn.step = "gn";
  ASSERT_TRUE(window.TakeSteps(1, gn).usable);
  const auto before = Values(window.problem());
  const auto expected = ClosedFormStep(window.problem());
  ASSERT_GT(LargestDifference(expected, before), 1e-6);

  ASSERT_TRUE(window.TakeSteps(1, gn).usable);
  EXPECT_LE(LargestDifference(Values(window.problem()), expected), 1e-10);
}

// The window keeps one solver and re-lays it out for every solve, reusing its
// buffers: after a step on ten states, marginalizing the oldest (one state and
// its landmarks fewer, a prior more) leaves a different layout, and the next
// step is still the closed form of the new window's cost.
TEST(WindowGaussNewton, AStepAfterTheWindowChangedEqualsTheClosedFormStep) {
  Window window(Model(), Flight().stereo());
  Flight().Build(window, Model(), kFirst, kFrames, kOffsetM);
  SolverOptions gn;
  gn.step = "gn";
  ASSERT_TRUE(window.TakeSteps(1, gn).usable);
  const size_t landmarks_before = window.landmarks().size();
  window.Marginalize({window.states().begin()->first}, {window.landmarks().begin()->first});
  ASSERT_LT(window.landmarks().size(), landmarks_before);
  const auto before = Values(window.problem());
  const auto expected = ClosedFormStep(window.problem());
  ASSERT_GT(LargestDifference(expected, before), 1e-6);

  ASSERT_TRUE(window.TakeSteps(1, gn).usable);
  EXPECT_LE(LargestDifference(Values(window.problem()), expected), 1e-10);
}

// A solver re-laid out onto a system of the same size but fewer couplings (the
// stereo residuals only: no IMU factor ties poses to speed/bias blocks) must
// give what a fresh assembly gives: the blocks only the first layout wrote are
// cleared, not left over (the assembly clears only the blocks it wrote last).
TEST(WindowGaussNewton, ARelayoutOntoFewerCouplingsLeavesNothingOfTheFirstSystem) {
  Window window(Model(), Flight().stereo());
  Flight().Build(window, Model(), kFirst, kFrames, kOffsetM);
  ceres::Problem& problem = window.problem();
  const GaussNewtonLayout all = window.Layout();
  GaussNewtonLayout stereo_only = all;
  stereo_only.residuals.clear();
  for (ceres::ResidualBlockId id : all.residuals) {
    if (problem.GetCostFunctionForResidualBlock(id)->num_residuals() == 3) stereo_only.residuals.push_back(id);
  }
  ASSERT_LT(stereo_only.residuals.size(), all.residuals.size());
  GaussNewtonSolver solver(&problem, all);
  ReducedSystem first;
  ASSERT_TRUE(solver.Reduce(&first));
  ASSERT_TRUE(solver.Reduce(&first));  // H reused: from here on only the written blocks are cleared
  solver.Relayout(stereo_only);
  ReducedSystem relaid;
  ASSERT_TRUE(solver.Reduce(&relaid));
  ReducedSystem fresh;
  ASSERT_TRUE(ReducedNormalEquations(&problem, stereo_only, &fresh));
  ASSERT_EQ(relaid.H.rows(), first.H.rows());
  ASSERT_GT((first.H - fresh.H).norm(), 1e-3 * fresh.H.norm());  // the IMU factors' blocks differ
  EXPECT_EQ((relaid.H - fresh.H).norm(), 0.0);
  EXPECT_EQ((relaid.b - fresh.b).norm(), 0.0);
}

/// r = x_dense[0] + x_eliminated[0] - 1 on a 2-dim dense and a 3-dim
/// eliminated block; entry `bad` of the Jacobian of block `block` (or of the
/// residual, block -1) is `value`.
class PoisonedCost final : public ceres::SizedCostFunction<1, 2, 3> {
 public:
  PoisonedCost(int block, int bad, double value) : block_(block), bad_(bad), value_(value) {}
  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    residuals[0] = x[0][0] + x[1][0] - 1.0;
    if (block_ < 0) residuals[0] = value_;
    if (jacobians == nullptr) return true;
    for (int k = 0; k < 2; ++k) {
      if (jacobians[k] == nullptr) continue;
      const int size = k == 0 ? 2 : 3;
      for (int c = 0; c < size; ++c) jacobians[k][c] = c == 0 ? 1.0 : 0.5;
      if (k == block_) jacobians[k][bad_] = value_;
    }
    return true;
  }

 private:
  int block_, bad_;
  double value_;
};

// A non-finite residual or Jacobian entry, in a dense or an eliminated block,
// fails the step (checked once per assembly on the sums it enters), and the
// values stay where they were.
TEST(GaussNewtonSolver, ANonFiniteResidualOrJacobianEntryFailsTheStep) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const auto& [block, bad, value] : std::vector<std::tuple<int, int, double>>{
           {-1, 0, nan}, {-1, 0, inf}, {0, 1, nan}, {0, 0, inf}, {1, 2, nan}, {1, 1, -inf}, {0, 1, 2.0}}) {
    ceres::Problem::Options options;
    options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
    ceres::Problem problem(options);
    double dense[2] = {0.2, 0.3};
    double eliminated[3] = {0.1, 0.0, 0.0};
    problem.AddParameterBlock(dense, 2);
    problem.AddParameterBlock(eliminated, 3);
    GaussNewtonLayout layout;
    layout.dense = {dense};
    layout.eliminated = {eliminated};
    // Enough residuals that the system is definite when nothing is poisoned.
    for (int k = 0; k < 6; ++k) {
      const bool poisoned = k == 3;
      layout.residuals.push_back(problem.AddResidualBlock(
          new PoisonedCost(poisoned ? block : 0, poisoned ? bad : 0, poisoned ? value : 1.0 + k), nullptr, dense,
          eliminated));
    }
    GaussNewtonSolver solver(&problem, layout);
    ReducedSystem system;
    const bool finite = std::isfinite(value);
    EXPECT_EQ(solver.Reduce(&system), finite) << block << " " << bad << " " << value;
    if (finite) continue;
    EXPECT_FALSE(solver.Step().ok) << block << " " << bad << " " << value;
    EXPECT_EQ(dense[0], 0.2);
    EXPECT_EQ(eliminated[0], 0.1);
  }
}

/// The normal equations of `layout` the sparse-Jacobian way (J from
/// Problem::Evaluate as a CRS matrix, then dense): H = J^T J, b = J^T r over
/// the dense columns followed by the eliminated ones.
void SparseJacobianNormalEquations(ceres::Problem& problem, const GaussNewtonLayout& layout, Eigen::MatrixXd* H,
                                   Eigen::VectorXd* b) {
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.residual_blocks = layout.residuals;
  evaluate.parameter_blocks = layout.dense;
  evaluate.parameter_blocks.insert(evaluate.parameter_blocks.end(), layout.eliminated.begin(), layout.eliminated.end());
  Eigen::MatrixXd J;
  Eigen::VectorXd r;
  EvaluateDense(problem, evaluate, &J, &r);
  *H = J.transpose() * J;
  *b = J.transpose() * r;
}

double RelativeDifference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) { return (a - b).norm() / b.norm(); }

// The per-residual-block assembly (a prior from its information, the upper
// block triangle, landmarks eliminated block by block) against the sparse
// Jacobian route on a realistic window: Huber active on the observations, a
// marginalization prior over states and landmarks moved off its linearization
// point. The reduced system (H, b) agrees to 1e-12 (measured 2e-16 and 9e-16),
// the step to 1e-10 (measured 1.5e-12).
TEST(WindowGaussNewton, PerBlockAssemblyEqualsTheSparseJacobianRouteWithHuberAndAPriorOffItsPoint) {
  ModelOptions model;  // Huber on (the default threshold)
  Window window(model, Flight().stereo());
  Flight().Build(window, model, kFirst, kFrames, kOffsetM);
  window.Marginalize({window.states().begin()->first}, {});
  SolverOptions gn;
  gn.step = "gn";
  ASSERT_TRUE(window.TakeSteps(1, gn).usable);
  ceres::Problem& problem = window.problem();
  // The window is realistic: Huber is active, the prior ties landmarks.
  ceres::Problem::EvaluateOptions plain;
  plain.apply_loss_function = false;
  double robust_cost = 0, plain_cost = 0;
  ASSERT_TRUE(problem.Evaluate(ceres::Problem::EvaluateOptions(), &robust_cost, nullptr, nullptr, nullptr));
  ASSERT_TRUE(problem.Evaluate(plain, &plain_cost, nullptr, nullptr, nullptr));
  ASSERT_LT(robust_cost, 0.99 * plain_cost);
  const GaussNewtonLayout layout = window.Layout();
  ASSERT_GT(layout.dense.size(), 2 * (kFrames - 1));
  ASSERT_FALSE(layout.eliminated.empty());

  Eigen::MatrixXd H;
  Eigen::VectorXd b;
  SparseJacobianNormalEquations(problem, layout, &H, &b);
  const Eigen::Index nd = H.rows() - 3 * static_cast<Eigen::Index>(layout.eliminated.size());
  const Eigen::Index ne = H.rows() - nd;
  const Eigen::LLT<Eigen::MatrixXd> Hee(H.bottomRightCorner(ne, ne));
  ASSERT_EQ(Hee.info(), Eigen::Success);
  const Eigen::MatrixXd reduced_H =
      H.topLeftCorner(nd, nd) - H.topRightCorner(nd, ne) * Hee.solve(H.bottomLeftCorner(ne, nd));
  const Eigen::VectorXd reduced_b = b.head(nd) - H.topRightCorner(nd, ne) * Hee.solve(b.tail(ne));
  ReducedSystem system;
  ASSERT_TRUE(ReducedNormalEquations(&problem, layout, &system));
  EXPECT_LE(RelativeDifference(system.H, reduced_H), 1e-12);
  EXPECT_LE(RelativeDifference(system.b, reduced_b), 1e-12);

  const Eigen::VectorXd dx = H.ldlt().solve(-b);
  std::vector<double*> blocks = layout.dense;
  blocks.insert(blocks.end(), layout.eliminated.begin(), layout.eliminated.end());
  std::vector<std::vector<double>> before;
  for (const double* block : blocks) before.emplace_back(block, block + problem.ParameterBlockSize(block));
  ASSERT_TRUE(window.TakeSteps(1, gn).usable);
  Eigen::VectorXd taken(dx.size());
  Eigen::Index col = 0;
  for (size_t k = 0; k < blocks.size(); ++k) {
    const int tangent = problem.ParameterBlockTangentSize(blocks[k]);
    const ceres::Manifold* manifold = problem.GetManifold(blocks[k]);
    if (manifold == nullptr) {
      for (int i = 0; i < tangent; ++i) taken[col + i] = blocks[k][i] - before[k][static_cast<size_t>(i)];
    } else {
      ASSERT_TRUE(manifold->Minus(blocks[k], before[k].data(), taken.data() + col));
    }
    col += tangent;
  }
  EXPECT_LE(RelativeDifference(taken, dx), 1e-10);
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

// An undamped step can overshoot a landmark out of the stereo factor's domain:
// a landmark estimated at ten times the depth its disparity says is stepped
// to far behind the camera. The window must undo such a step (else every
// later solve fails to linearize until the observation leaves the window).
// Largest difference between two windows' values, matched by state and
// landmark ids (their blocks live at different addresses).
double LargestDifferenceByIds(const Window& a, const Window& b) {
  double largest = 0;
  const auto compare = [&](const double* x, const double* y, int size) {
    for (int i = 0; i < size; ++i) largest = std::max(largest, std::abs(x[i] - y[i]));
  };
  for (const auto& [id, state] : b.states()) {
    compare(a.state(id).pose, state.pose, 7);
    compare(a.state(id).speed_bias, state.speed_bias, 9);
  }
  for (const auto& [id, landmark] : b.landmarks()) compare(a.landmark(id).p_w, landmark.p_w, 3);
  return largest;
}

// An observation whose landmark sits at 10x the depth its disparity says: the
// undamped step puts the landmark behind the camera. The step is undone, the
// observation (the landmark's only one) is dropped with its landmark, and the
// step is taken again: it equals the step of the window that never had them.
TEST(WindowGaussNewton, AStepThatMovesALandmarkBehindTheCameraIsRetakenWithoutTheOutlier) {
  constexpr int kStates = 3;
  Window window(Model(), Flight().stereo());
  Flight().Build(window, Model(), kFirst, kStates);
  Window clean(Model(), Flight().stereo());
  Flight().Build(clean, Model(), kFirst, kStates);
  const StateId last(kStates - 1);
  const State& state = window.state(last);
  const Landmark* seen = nullptr;
  for (const auto& [id, landmark] : window.landmarks()) {
    if (landmark.observed_from.count(last)) seen = &landmark;
  }
  ASSERT_NE(seen, nullptr);
  Eigen::Vector3d z_px;
  ASSERT_TRUE(StereoFactor::Project(Flight().stereo(), state.p_w_b(), state.q_w_b(), seen->position(), &z_px));
  const LandmarkId far(1000000);
  window.AddLandmark(far, state.p_w_b() + 10 * (seen->position() - state.p_w_b()));
  window.AddObservation(last, far, z_px);
  const double* far_block = window.landmark(far).p_w;
  const std::vector<double>& stepped = ClosedFormStep(window.problem()).at(far_block);
  ASSERT_FALSE(StereoFactor::Project(Flight().stereo(), state.p_w_b(), state.q_w_b(),
                                     Eigen::Vector3d(stepped[0], stepped[1], stepped[2]), &z_px))
      << "the step should end behind the camera";
  ASSERT_EQ(LargestDifferenceByIds(window, clean), 0.0);

  SolverOptions gn;
  gn.step = "gn";
  const SolveReport report = window.TakeSteps(1, gn);
  EXPECT_TRUE(report.usable);
  EXPECT_EQ(report.iterations, 1);
  EXPECT_EQ(window.health().rejected_steps, 1);
  EXPECT_EQ(window.health().dropped_observations, 1);
  EXPECT_EQ(window.health().failed_solves, 0);
  EXPECT_FALSE(window.HasLandmark(far));
  ASSERT_EQ(window.removals().dropped_landmarks.size(), 1u);
  EXPECT_EQ(window.removals().dropped_landmarks[0], far);

  ASSERT_TRUE(clean.TakeSteps(1, gn).usable);
  EXPECT_LE(LargestDifferenceByIds(window, clean), 1e-12);
  double cost = 0;
  EXPECT_TRUE(window.problem().Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, nullptr));
}

}  // namespace
}  // namespace vio
