// The caller's SolveControl (solve_control.h) in the window's solves: a stop
// request ends a solve between iterations at the iterate a solve capped there
// reaches (Gauss-Newton and Levenberg-Marquardt), and hooks that never stop
// change no value. Exactly for gn; to 1e-9 for lm, whose Ceres orders blocks
// by address inside an elimination group (two windows: two heap layouts).
#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "synthetic_window.h"
#include "vio/estimator/solve_control.h"
#include "vio/estimator/window.h"

namespace vio {
namespace {

constexpr int kFirst = 30;
constexpr int kFrames = 6;
constexpr double kOffsetM = 0.05;

const test::SyntheticFlight& Flight() {
  static const test::SyntheticFlight flight(6.0, 11);
  return flight;
}

ModelOptions Model() { return ModelOptions{}; }

// Largest difference between two windows' values, matched by ids.
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

double Tolerance(const std::string& step) { return step == "gn" ? 0.0 : 1e-9; }

SolverOptions Options(const std::string& step) {
  SolverOptions options;
  options.step = step;
  options.max_iterations = 10;
  options.function_tolerance = 1e-12;
  return options;
}

class SolveControlTest : public ::testing::TestWithParam<std::string> {};

// Asked to stop once it has heard two iterations: the solve ends there, with
// the values of the same solve capped at two iterations.
TEST_P(SolveControlTest, AStopRequestEndsTheSolveAtTheIterateReached) {
  const SolverOptions options = Options(GetParam());
  Window stopped(Model(), Flight().stereo());
  Flight().Build(stopped, Model(), kFirst, kFrames, kOffsetM);
  std::vector<SolveProgress> heard;
  SolveControl control;
  control.progress = [&](const SolveProgress& p) { heard.push_back(p); };
  control.stop = [&] { return !heard.empty() && heard.back().iteration >= 2; };
  stopped.SetSolveControl(control);
  const SolveReport report = stopped.Solve(options);
  EXPECT_TRUE(report.stopped);
  EXPECT_TRUE(report.usable);
  EXPECT_FALSE(report.converged);
  EXPECT_EQ(stopped.health().stopped_solves, 1);
  ASSERT_FALSE(heard.empty());
  EXPECT_EQ(heard.back().iteration, 2);
  EXPECT_EQ(heard.back().max_iterations, options.max_iterations);
  EXPECT_EQ(heard.back().cost, report.final_cost);
  EXPECT_LT(heard.back().cost, heard.back().initial_cost);

  Window capped(Model(), Flight().stereo());
  Flight().Build(capped, Model(), kFirst, kFrames, kOffsetM);
  SolverOptions two = options;
  two.max_iterations = 2;
  const SolveReport capped_report = capped.Solve(two);
  EXPECT_FALSE(capped_report.stopped);
  EXPECT_EQ(capped.health().stopped_solves, 0);
  EXPECT_LE(LargestDifferenceByIds(stopped, capped), Tolerance(GetParam()));
}

// Hooks that never stop leave every value as a solve without them.
TEST_P(SolveControlTest, HooksThatNeverStopChangeNothing) {
  const SolverOptions options = Options(GetParam());
  Window watched(Model(), Flight().stereo());
  Flight().Build(watched, Model(), kFirst, kFrames, kOffsetM);
  int asked = 0;
  int heard = 0;
  SolveControl control;
  control.stop = [&] { return ++asked < 0; };
  control.progress = [&](const SolveProgress&) { ++heard; };
  watched.SetSolveControl(control);
  const SolveReport report = watched.Solve(options);
  EXPECT_FALSE(report.stopped);
  EXPECT_GE(asked, report.iterations);
  EXPECT_GE(heard, report.iterations);

  Window plain(Model(), Flight().stereo());
  Flight().Build(plain, Model(), kFirst, kFrames, kOffsetM);
  const SolveReport plain_report = plain.Solve(options);
  EXPECT_EQ(report.iterations, plain_report.iterations);
  EXPECT_NEAR(report.final_cost, plain_report.final_cost, Tolerance(GetParam()) * plain_report.final_cost);
  EXPECT_LE(LargestDifferenceByIds(watched, plain), Tolerance(GetParam()));
}

INSTANTIATE_TEST_SUITE_P(Steps, SolveControlTest, ::testing::Values("gn", "lm"));

}  // namespace
}  // namespace vio
