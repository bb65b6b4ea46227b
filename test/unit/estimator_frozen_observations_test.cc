// Window::SolveSparse(options, frozen), batch's periodic solves with the
// observations from frozen states summarized per landmark
// (frozen_observations.h): at the point where the states froze, the summary
// has the cost, gradient and Gauss-Newton Hessian of the residuals it
// replaces, so the first Levenberg-Marquardt step is the one the full cost
// takes, to 1e-8.
#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "synthetic_window.h"
#include "vio/estimator/window.h"

namespace vio {
namespace {

constexpr int kFrames = 12;
constexpr int kFrozen = 6;
constexpr int kFirst = 40;
constexpr double kOffsetM = 0.02;

const test::SyntheticFlight& Flight() {
  static const test::SyntheticFlight flight(5.0, 11);
  return flight;
}

std::vector<double> AllValues(const Window& window) {
  std::vector<double> values;
  for (const auto& [id, s] : window.states()) {
    values.insert(values.end(), s.pose, s.pose + 7);
    values.insert(values.end(), s.speed_bias, s.speed_bias + 9);
  }
  for (const auto& [id, landmark] : window.landmarks()) values.insert(values.end(), landmark.p_w, landmark.p_w + 3);
  return values;
}

double MaxDifference(const std::vector<double>& a, const std::vector<double>& b) {
  EXPECT_EQ(a.size(), b.size());
  double worst = 0;
  for (size_t i = 0; i < a.size() && i < b.size(); ++i) worst = std::max(worst, std::abs(a[i] - b[i]));
  return worst;
}

// Freezes the first kFrozen states as batch does (summarized into `frozen` when
// given, then constant) and the landmarks only they see.
void Freeze(Window& window, FrozenObservations* frozen) {
  for (int k = 0; k < kFrozen; ++k) {
    if (frozen != nullptr) window.SummarizeObservationsOf(StateId(k), *frozen);
    window.SetStateConstant(StateId(k), true);
  }
  for (const auto& [id, landmark] : window.landmarks()) {
    if (landmark.observed_from.rbegin()->value < kFrozen) window.SetLandmarkConstant(id, true);
  }
}

struct Solved {
  SolveReport report;
  std::vector<double> values;
};

SolverOptions Tight(int iterations) {
  SolverOptions solver;
  solver.step = "lm";
  solver.linear_solver = "dense";
  solver.max_iterations = iterations;
  solver.function_tolerance = 1e-16;
  solver.parameter_tolerance = 1e-14;
  return solver;
}

// `presolved`: the whole window solved first and the states that stay active
// moved by kOffsetM, as batch's states freeze at the values its solves left.
Solved OneStep(bool summarized, int iterations, bool presolved = false) {
  const ModelOptions model;
  Window window(model, Flight().stereo());
  Flight().Build(window, model, kFirst, kFrames, kOffsetM);
  if (presolved) {
    EXPECT_TRUE(window.SolveSparse(Tight(100)).usable);
    for (int k = kFrozen; k < kFrames; ++k) {
      State& s = window.state(StateId(k));
      s.SetPose(s.p_w_b() + Eigen::Vector3d::Constant(k % 2 ? kOffsetM : -kOffsetM), s.q_w_b());
    }
  }
  FrozenObservations frozen;
  Freeze(window, summarized ? &frozen : nullptr);
  if (summarized) {
    EXPECT_EQ(frozen.skipped, 0);
    EXPECT_FALSE(frozen.landmarks.empty());
  }
  const SolverOptions solver = Tight(iterations);
  Solved solved;
  solved.report = summarized ? window.SolveSparse(solver, frozen) : window.SolveSparse(solver);
  solved.values = AllValues(window);
  return solved;
}

TEST(FrozenObservations, FirstStepIsTheFullCostsStep) {
  const Solved start = OneStep(false, 0);
  const Solved full = OneStep(false, 1);
  const Solved summarized = OneStep(true, 1);
  ASSERT_TRUE(full.report.usable);
  ASSERT_TRUE(summarized.report.usable);
  EXPECT_NEAR(summarized.report.initial_cost, full.report.initial_cost, 1e-8 * full.report.initial_cost);
  EXPECT_GT(MaxDifference(full.values, start.values), 1e-4);  // the step moved the states
  EXPECT_LT(MaxDifference(summarized.values, full.values), 1e-8);
}

// Frozen at a minimum, as in batch, the summarized solve converges back to it:
// the two differ only by the frozen residuals' terms beyond second order over
// the landmarks' moves.
TEST(FrozenObservations, ConvergesNearTheFullCostsMinimum) {
  const Solved full = OneStep(false, 100, true);
  const Solved summarized = OneStep(true, 100, true);
  ASSERT_TRUE(summarized.report.usable);
  EXPECT_LT(MaxDifference(summarized.values, full.values), 1e-4);
  EXPECT_NEAR(summarized.report.final_cost, full.report.final_cost, 1e-3 * full.report.final_cost);
}

}  // namespace
}  // namespace vio
