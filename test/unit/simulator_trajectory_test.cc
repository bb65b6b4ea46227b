// The synthetic flight: analytic derivatives, limits, static start, closure;
// ground-truth interpolation.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "vio/simulator/trajectory.h"

namespace vio::tools {
namespace {

Eigen::Vector3d RotationLog(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

// Times that cover the static start, the ramp (and its ends) and full pace.
std::vector<double> ProbeTimes() {
  return {1.0, 3.0, 3.001, 3.4, 4.0, 4.999, 5.0, 5.2, 7.7, 12.3, 25.0, 41.9};
}

TEST(SyntheticTrajectoryTest, VelocityAccelerationAndRateMatchFiniteDifferences) {
  const SyntheticTrajectory trajectory{SyntheticTrajectoryOptions()};
  const double h = 1e-5;
  for (double t : ProbeTimes()) {
    const KinematicState s = trajectory.Evaluate(t);
    const KinematicState before = trajectory.Evaluate(t - h), after = trajectory.Evaluate(t + h);
    EXPECT_LT((s.v_w_b - (after.p_w_b - before.p_w_b) / (2 * h)).norm(), 1e-6) << "t=" << t;
    EXPECT_LT((s.a_w_b - (after.v_w_b - before.v_w_b) / (2 * h)).norm(), 1e-5) << "t=" << t;
    const Eigen::Vector3d omega_fd =
        RotationLog(before.q_w_b.toRotationMatrix().transpose() * after.q_w_b.toRotationMatrix()) / (2 * h);
    EXPECT_LT((s.omega_b - omega_fd).norm(), 1e-5) << "t=" << t;
  }
}

TEST(SyntheticTrajectoryTest, StartsAtRestAndRespectsLimits) {
  SyntheticTrajectoryOptions options;
  options.max_speed_m_s = 1.7;
  options.max_rotation_rate_rad_s = 0.9;
  const SyntheticTrajectory trajectory(options);
  const KinematicState start = trajectory.Evaluate(0.0);
  for (double t = 0.0; t <= options.static_duration_s; t += 0.25) {
    const KinematicState s = trajectory.Evaluate(t);
    EXPECT_LT((s.p_w_b - start.p_w_b).norm(), 1e-12);
    EXPECT_EQ(s.v_w_b.norm(), 0.0);
    EXPECT_EQ(s.a_w_b.norm(), 0.0);
    EXPECT_EQ(s.omega_b.norm(), 0.0);
  }
  double max_speed = 0.0, max_rate = 0.0;
  for (double t = 0.0; t < 60.0; t += 0.005) {
    const KinematicState s = trajectory.Evaluate(t);
    max_speed = std::max(max_speed, s.v_w_b.norm());
    max_rate = std::max(max_rate, s.omega_b.norm());
    EXPECT_TRUE(((s.p_w_b - options.center_w).cwiseAbs() - options.half_extent_m).maxCoeff() <= 1e-9);
  }
  EXPECT_LE(max_speed, options.max_speed_m_s);
  EXPECT_LE(max_rate, options.max_rotation_rate_rad_s);
  EXPECT_GT(std::max(max_speed / options.max_speed_m_s, max_rate / options.max_rotation_rate_rad_s), 0.95);
}

TEST(SyntheticTrajectoryTest, FlightIsClosedAfterTheRamp) {
  const SyntheticTrajectory trajectory{SyntheticTrajectoryOptions()};
  const double t = 9.0;  // after static + ramp
  const KinematicState a = trajectory.Evaluate(t), b = trajectory.Evaluate(t + trajectory.period_s());
  EXPECT_LT((a.p_w_b - b.p_w_b).norm(), 1e-9);
  EXPECT_LT((a.v_w_b - b.v_w_b).norm(), 1e-9);
  EXPECT_LT(a.q_w_b.angularDistance(b.q_w_b), 1e-9);
}

TEST(SyntheticTrajectoryTest, CamerasLookHorizontallyWhenLevel) {
  // EuRoC mounting: body x up, body z (camera optical axis) forward.
  const Eigen::Matrix3d R_r_b = HeadingFromBody();
  EXPECT_NEAR(R_r_b.determinant(), 1.0, 1e-12);
  EXPECT_LT((R_r_b * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitZ()).norm(), 1e-12);
  EXPECT_LT((R_r_b * Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitX()).norm(), 1e-12);
}

TEST(InterpolatePoseTest, SlerpAndLinearBetweenSamplesNulloptOutside) {
  std::vector<GroundTruthState> gt(2);
  gt[0].t_ns = 1000;
  gt[1].t_ns = 2000;
  gt[1].p_w_b = Eigen::Vector3d(1.0, -2.0, 4.0);
  gt[1].q_w_b = Eigen::Quaterniond(Eigen::AngleAxisd(0.8, Eigen::Vector3d::UnitZ()));
  const auto mid = InterpolatePose(gt, 1250);
  ASSERT_TRUE(mid.has_value());
  EXPECT_LT((mid->translation() - Eigen::Vector3d(0.25, -0.5, 1.0)).norm(), 1e-12);
  EXPECT_NEAR(Eigen::AngleAxisd(mid->linear()).angle(), 0.2, 1e-12);
  EXPECT_TRUE(InterpolatePose(gt, 1000).has_value());
  EXPECT_TRUE(InterpolatePose(gt, 2000).has_value());
  EXPECT_FALSE(InterpolatePose(gt, 999).has_value());
  EXPECT_FALSE(InterpolatePose(gt, 2001).has_value());
}

// 1 m/s along x at 200 Hz with one 10 cm glitch: exactly that step is found.
TEST(GroundTruthJumpsTest, FindsAStepThatDisagreesWithTheVelocity) {
  std::vector<GroundTruthState> gt(400);
  for (size_t i = 0; i < gt.size(); ++i) {
    gt[i].t_ns = static_cast<Timestamp>(i) * 5'000'000;
    gt[i].p_w_b = Eigen::Vector3d(0.005 * static_cast<double>(i) + (i >= 200 ? 0.1 : 0.0), 0, 0);
    gt[i].v_w_b = Eigen::Vector3d(1, 0, 0);
  }
  const std::vector<GroundTruthJump> jumps = FindGroundTruthJumps(gt, 5.0);
  ASSERT_EQ(jumps.size(), 1u);
  EXPECT_EQ(jumps[0].t_ns, 199 * 5'000'000);
  EXPECT_NEAR(jumps[0].step_m, 0.105, 1e-12);
  EXPECT_NEAR(jumps[0].speed_m_s, 21.0, 1e-9);
  EXPECT_NEAR(jumps[0].velocity_m_s, 1.0, 1e-12);
  EXPECT_EQ(jumps[0].end_ns, 200 * 5'000'000);
  EXPECT_LT((jumps[0].excess_m - Eigen::Vector3d(0.1, 0, 0)).norm(), 1e-12);
  // Without velocities (TUM text) nothing can be judged.
  for (GroundTruthState& s : gt) s.has_velocity_and_biases = false;
  EXPECT_TRUE(FindGroundTruthJumps(gt, 5.0).empty());
}

// Two glitches, one of them back: removing them leaves a ground truth whose
// every step agrees with its velocity, the samples before the first
// untouched, and orientation and velocity as they were.
TEST(GroundTruthJumpsTest, RemovingThemLeavesAGroundTruthTheVelocityExplains) {
  std::vector<GroundTruthState> gt(600);
  for (size_t i = 0; i < gt.size(); ++i) {
    const double t = 0.005 * static_cast<double>(i);
    gt[i].t_ns = static_cast<Timestamp>(i) * 5'000'000;
    gt[i].p_w_b = Eigen::Vector3d(t, std::sin(t), 0.5 * t * t);
    gt[i].v_w_b = Eigen::Vector3d(1, std::cos(t), t);
    gt[i].q_w_b = Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * t, Eigen::Vector3d::UnitZ()));
    if (i >= 200) gt[i].p_w_b += Eigen::Vector3d(0.1, -0.05, 0.02);
    if (i >= 400) gt[i].p_w_b -= Eigen::Vector3d(0.0, 0.2, 0.0);
  }
  const std::vector<GroundTruthJump> jumps = FindGroundTruthJumps(gt, 5.0);
  ASSERT_EQ(jumps.size(), 2u);
  const std::vector<GroundTruthState> repaired = RemoveGroundTruthJumps(gt, jumps);
  ASSERT_EQ(repaired.size(), gt.size());
  EXPECT_TRUE(FindGroundTruthJumps(repaired, 5.0).empty());
  // Between samples the velocity explains the steps to the trapezoid rule's
  // error; through each former jump as well.
  for (size_t i : {199u, 399u}) {
    const Eigen::Vector3d step = repaired[i + 1].p_w_b - repaired[i].p_w_b;
    EXPECT_LT((step - 0.005 * 0.5 * (repaired[i].v_w_b + repaired[i + 1].v_w_b)).norm(), 1e-5) << i;
  }
  for (size_t i = 0; i < gt.size(); ++i) {
    if (i < 200) {
      EXPECT_EQ(repaired[i].p_w_b, gt[i].p_w_b) << i;
    }
    EXPECT_EQ(repaired[i].v_w_b, gt[i].v_w_b);
    EXPECT_EQ(repaired[i].q_w_b.coeffs(), gt[i].q_w_b.coeffs());
  }
  // Removing nothing changes nothing.
  const std::vector<GroundTruthState> same = RemoveGroundTruthJumps(gt, {});
  for (size_t i = 0; i < gt.size(); ++i) EXPECT_EQ(same[i].p_w_b, gt[i].p_w_b);
}

}  // namespace
}  // namespace vio::tools
