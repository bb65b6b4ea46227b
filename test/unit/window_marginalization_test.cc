// The window manager's marginalization on a real visual-inertial window: at
// the optimum, marginalizing the oldest state (with its landmarks, or keeping
// the landmarks other states see) must leave the optimum of what remains
// where it was (Theorem 2.2.2 is exact to first order and the gradient is
// zero there), and the problem must keep solving afterwards.
#include <gtest/gtest.h>

#include "vio/estimator/imu_preintegration.h"
#include "vio/estimator/policy.h"
#include "vio/estimator/window.h"
#include "vio/frontend/stereo_rectifier.h"
#include "vio/tools/simulator.h"
#include "vio/tools/stereo_frames.h"

namespace vio {
namespace {

constexpr int kFrames = 8;

struct WindowFixture {
  tools::Simulation sim;
  std::vector<StereoFrame> frames;
  RectifiedStereo stereo;
  ModelOptions model;

  WindowFixture() {
    tools::SimulatorOptions options;
    options.duration_s = 6.0;
    options.seed = 7;
    sim = tools::BuildSimulation(options);
    const frontend::StereoRectifier rectifier(sim.dataset.cameras[0], sim.dataset.cameras[1]);
    stereo = rectifier.rectified();
    tools::StereoFramesReport report;
    frames = tools::StereoFramesFromFeatures(sim.dataset.features, sim.dataset.frames[0], rectifier, 2.0, &report);
    model.huber_px = 0;  // a pure least-squares cost
  }

  const tools::GroundTruthState& NearestGroundTruth(Timestamp t_ns) const {
    const auto& gt = sim.dataset.groundtruth;
    auto it = std::lower_bound(gt.begin(), gt.end(), t_ns,
                               [](const tools::GroundTruthState& g, Timestamp t) { return g.t_ns < t; });
    return it == gt.end() ? gt.back() : *it;
  }

  // States at frames [first, first + kFrames) of the moving part, at ground
  // truth, linked by IMU factors; every observation added.
  void Build(Window& window, int first) const {
    for (int k = 0; k < kFrames; ++k) {
      const StateId id(k);
      const tools::GroundTruthState& gt = NearestGroundTruth(frames[first + k].t_ns);
      State& s = window.AddState(id, frames[first + k].t_ns);
      s.SetPose(gt.p_w_b, gt.q_w_b);
      s.SetSpeedBias(gt.v_w_b, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
      if (k == 0) {
        StatePrior prior;
        prior.pose_covariance = Eigen::Matrix<double, 6, 6>::Identity() * 1e-6;
        prior.speed_bias_sigma << Eigen::Vector3d::Constant(0.1), Eigen::Vector3d::Constant(0.01),
            Eigen::Vector3d::Constant(0.1);
        window.AddStatePrior(id, prior);
      } else {
        window.AddImuFactor(StateId(k - 1), id,
                            PreintegrateBetween(sim.dataset.imu, frames[first + k - 1].t_ns, frames[first + k].t_ns,
                                                ImuBias{}, sim.dataset.imu_calibration));
      }
      AddStereoObservations(frames[first + k], id, model, window);
    }
  }
};

SolverOptions Converge() {
  SolverOptions solver;
  solver.max_iterations = 100;
  solver.max_solver_time_s = 60;
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
  Window window(fixture.model, fixture.stereo);
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

TEST(WindowMarginalization, DroppingALandmarkRemovesItsObservations) {
  static const WindowFixture fixture;
  Window window(fixture.model, fixture.stereo);
  fixture.Build(window, /*first=*/70);
  const LandmarkId id = window.landmarks().begin()->first;
  const int observations = static_cast<int>(window.landmark(id).observed_from.size());
  const int residuals_before = window.problem().NumResidualBlocks();
  window.DropLandmark(id);
  EXPECT_FALSE(window.HasLandmark(id));
  EXPECT_EQ(window.problem().NumResidualBlocks(), residuals_before - observations);
}

}  // namespace
}  // namespace vio
