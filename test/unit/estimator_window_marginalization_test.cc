// The window manager's marginalization on a real visual-inertial window: at
// the optimum, marginalizing the oldest state (with its landmarks, or keeping
// the landmarks other states see) must leave the optimum of what remains
// where it was (Theorem 2.2.2 is exact to first order and the gradient is
// zero there), and the problem must keep solving afterwards.
#include <cmath>

#include <gtest/gtest.h>

#include "synthetic_window.h"
#include "vio/estimator/policy.h"
#include "vio/estimator/window.h"

namespace vio {
namespace {

constexpr int kFrames = 8;

// The window of kFrames states the tests marginalize from (no robust loss: a
// pure least-squares cost).
struct WindowFixture {
  test::SyntheticFlight flight{6.0, 7};
  ModelOptions model = [] {
    ModelOptions m;
    m.huber_px = 0;
    return m;
  }();

  void Build(Window& window, int first) const { flight.Build(window, model, first, kFrames); }
};

SolverOptions Converge() {
  SolverOptions solver;
  solver.max_iterations = 100;
  solver.function_tolerance = 1e-16;
  return solver;
}

double LargestPoseChange(const Window& window, const std::map<StateId, State>& before) {
  double change = 0;
  for (const auto& [id, s] : window.states()) {
    const State& b = before.at(id);
    change = std::max(change, (s.p_w_b() - b.p_w_b()).norm());
    change = std::max(change, s.q_w_b().angularDistance(b.q_w_b()));
    change = std::max(change, (s.v_w_b() - b.v_w_b()).norm());
  }
  return change;
}

void ExpectMarginalizingAtTheOptimumKeepsIt(bool keep_landmarks) {
  static const WindowFixture fixture;
  Window window(fixture.model, fixture.flight.stereo());
  fixture.Build(window, /*first=*/70);
  window.Solve(Converge());
  const std::map<StateId, State> optimum = window.states();

  const std::vector<StateId> leaving = {StateId(0)};
  const std::vector<LandmarkId> landmarks =
      keep_landmarks ? LandmarksOnlySeenFrom(window, leaving) : LandmarksSeenFrom(window, leaving);
  // Either way the leaving state saw landmarks; with keep_landmarks those
  // others still see stay, tied to the rest by the prior.
  ASSERT_FALSE(LandmarksSeenFrom(window, leaving).empty());
  if (!keep_landmarks) {
    ASSERT_FALSE(landmarks.empty());
  }
  const size_t landmarks_before = window.landmarks().size();
  window.Marginalize(leaving, landmarks);
  EXPECT_EQ(window.states().size(), static_cast<size_t>(kFrames - 1));
  EXPECT_EQ(window.landmarks().size(), landmarks_before - landmarks.size());
  EXPECT_GE(window.num_priors(), 1);

  const SolveReport report = window.Solve(Converge());
  EXPECT_TRUE(report.usable);
  EXPECT_LT(LargestPoseChange(window, optimum), 1e-6);
}

TEST(WindowMarginalization, OldestStateWithAllItsLandmarksLeavesTheOptimumInPlace) {
  ExpectMarginalizingAtTheOptimumKeepsIt(/*keep_landmarks=*/false);
}

TEST(WindowMarginalization, OldestStateKeepingSharedLandmarksLeavesTheOptimumInPlace) {
  ExpectMarginalizingAtTheOptimumKeepsIt(/*keep_landmarks=*/true);
}

// What leaves is reported as it was last estimated (a fixed-lag smoother's
// output, Estimator::LastEstimates): the marginalized state's values at the
// moment it left, not its values when it was added.
TEST(WindowMarginalization, LeavingStatesAreReportedAsLastEstimated) {
  static const WindowFixture fixture;
  Window window(fixture.model, fixture.flight.stereo());
  fixture.Build(window, /*first=*/70);
  State& s0 = window.state(StateId(0));
  s0.SetPose(s0.p_w_b() + Eigen::Vector3d(0.01, -0.02, 0.005), s0.q_w_b());  // as a solve would move it
  const State solved = s0;
  window.ClearRemovals();
  window.Marginalize({StateId(0)}, LandmarksSeenFrom(window, {StateId(0)}));
  ASSERT_EQ(window.removals().leaving_states.size(), 1u);
  const State& left = window.removals().leaving_states.front();
  EXPECT_EQ(left.id, StateId(0));
  EXPECT_EQ(left.t_ns, solved.t_ns);
  for (int k = 0; k < 7; ++k) EXPECT_EQ(left.pose[k], solved.pose[k]) << k;
  for (int k = 0; k < 9; ++k) EXPECT_EQ(left.speed_bias[k], solved.speed_bias[k]) << k;
}

TEST(WindowMarginalization, DroppingALandmarkRemovesItsObservations) {
  static const WindowFixture fixture;
  Window window(fixture.model, fixture.flight.stereo());
  fixture.Build(window, /*first=*/70);
  const LandmarkId id = window.landmarks().begin()->first;
  const int observations = static_cast<int>(window.landmark(id).observed_from.size());
  const int residuals_before = window.problem().NumResidualBlocks();
  window.DropLandmark(id);
  EXPECT_FALSE(window.HasLandmark(id));
  EXPECT_EQ(window.problem().NumResidualBlocks(), residuals_before - observations);
}

// A landmark at the camera centre of the leaving state does not evaluate
// (StereoFactor fails below 1 mm depth): marginalization drops its residual
// with a warning instead of failing, and the window keeps solving.
TEST(WindowMarginalization, AResidualThatDoesNotEvaluateIsDroppedNotFatal) {
  static const WindowFixture fixture;
  Window window(fixture.model, fixture.flight.stereo());
  fixture.Build(window, /*first=*/70);
  const State& oldest = window.state(StateId(0));
  const Eigen::Vector3d camera_centre = oldest.p_w_b() + oldest.q_w_b() * window.stereo().T_b_cl.translation();
  const LandmarkId bad(1'000'000);
  window.AddLandmark(bad, camera_centre);
  window.AddObservation(StateId(0), bad, Eigen::Vector3d(300, 290, 200));
  EXPECT_TRUE(std::isinf(window.ObservationError(StateId(0), bad)));
  std::vector<LandmarkId> landmarks = LandmarksSeenFrom(window, {StateId(0)});
  EXPECT_NO_THROW(window.Marginalize({StateId(0)}, landmarks));
  EXPECT_EQ(window.health().dropped_residuals, 1);
  EXPECT_FALSE(window.HasLandmark(bad));
  EXPECT_TRUE(window.Solve(Converge()).usable);
  EXPECT_EQ(window.health().failed_solves, 0);
}

}  // namespace
}  // namespace vio
