// `--init=groundtruth` from a pose-only (TUM) ground truth: velocity and both
// biases derived from the poses and the IMU come back to the simulated truth;
// a full-state (EuRoC CSV) ground truth is used as it is.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "vio/dataset/groundtruth_init.h"
#include "vio/simulator/imu.h"
#include "vio/simulator/trajectory.h"

namespace vio::tools {
namespace {

// A noise-free synthetic flight with constant, non-zero biases.
ImuSynthesis Flight(std::uint64_t seed) {
  SyntheticTrajectoryOptions flight;
  flight.static_duration_s = 0.5;
  flight.ramp_duration_s = 0.5;
  ImuSynthesisOptions imu;
  imu.noise_scale = 0.0;
  imu.initial_gyro_bias_sigma_rad_s = 0.05;
  imu.initial_accel_bias_sigma_m_s2 = 0.3;
  std::mt19937_64 rng(seed);
  return SynthesizeImu(SyntheticTrajectory(flight), 0, 8.0, imu, &rng);
}

std::vector<GroundTruthState> PosesOnly(std::vector<GroundTruthState> gt) {
  for (GroundTruthState& s : gt) {
    s.v_w_b.setZero();
    s.gyro_bias.setZero();
    s.accel_bias.setZero();
    s.has_velocity_and_biases = false;
  }
  return gt;
}

TEST(GroundTruthInitTest, DerivesVelocityAndBiasesFromPosesAndImu) {
  const ImuSynthesis flight = Flight(7);
  const std::vector<GroundTruthState> poses = PosesOnly(flight.groundtruth);
  const GroundTruthState& truth = flight.groundtruth[1000];  // 5 s in, at full pace
  ASSERT_GT(truth.v_w_b.norm(), 0.5);
  ASSERT_GT(truth.gyro_bias.norm(), 0.01);
  ASSERT_GT(truth.accel_bias.norm(), 0.05);
  const std::optional<InitialState> state = GroundTruthInitialState(poses, flight.imu, truth.t_ns, 9.81, 1.0);
  ASSERT_TRUE(state.has_value());
  EXPECT_LT((state->p_w_b - truth.p_w_b).norm(), 1e-9);
  EXPECT_LT(state->q_w_b.angularDistance(truth.q_w_b), 1e-9);
  // Central differences of step h err by O(h^2) times the motion's third
  // derivatives: millimetres per second and milliradians per second here.
  EXPECT_LT((state->v_w_b - truth.v_w_b).norm(), 0.01 * truth.v_w_b.norm());
  EXPECT_LT((state->gyro_bias - truth.gyro_bias).norm(), 2e-3);
  EXPECT_LT((state->accel_bias - truth.accel_bias).norm(), 0.02);
}

TEST(GroundTruthInitTest, UsesAFullStateAsItIs) {
  const ImuSynthesis flight = Flight(8);
  const GroundTruthState& truth = flight.groundtruth[1000];
  const std::optional<InitialState> state =
      GroundTruthInitialState(flight.groundtruth, flight.imu, truth.t_ns, 9.81, 1.0);
  ASSERT_TRUE(state.has_value());
  EXPECT_EQ(state->v_w_b, truth.v_w_b);
  EXPECT_EQ(state->gyro_bias, truth.gyro_bias);
  EXPECT_EQ(state->accel_bias, truth.accel_bias);
}

TEST(GroundTruthInitTest, NothingOutsideTheGroundTruthSpan) {
  const ImuSynthesis flight = Flight(9);
  EXPECT_FALSE(GroundTruthInitialState(flight.groundtruth, flight.imu, flight.groundtruth.front().t_ns - 1, 9.81, 1.0));
  EXPECT_FALSE(GroundTruthInitialState(flight.groundtruth, flight.imu, flight.groundtruth.back().t_ns + 1, 9.81, 1.0));
}

// The same flight in a world tilted by 30 degrees about x (a ground truth
// fixed to a tilted target): the IMU's up is 30 degrees from its z.
TEST(GroundTruthInitTest, TiltOfTheGroundTruthWorldIsMeasuredFromTheImu) {
  const ImuSynthesis flight = Flight(3);
  const std::optional<double> level = GroundTruthTiltDeg(flight.groundtruth, flight.imu, 9.81);
  ASSERT_TRUE(level.has_value());
  EXPECT_LT(*level, 2.0);  // an accelerometer bias of 0.3 m/s^2 tilts the mean by up to 1.8 degrees
  const Eigen::Quaterniond tilt(Eigen::AngleAxisd(30.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()));
  std::vector<GroundTruthState> tilted = flight.groundtruth;
  for (GroundTruthState& s : tilted) {
    s.p_w_b = tilt * s.p_w_b;
    s.q_w_b = tilt * s.q_w_b;
  }
  const std::optional<double> measured = GroundTruthTiltDeg(tilted, flight.imu, 9.81);
  ASSERT_TRUE(measured.has_value());
  EXPECT_NEAR(*measured, 30.0, 2.0);
  EXPECT_FALSE(GroundTruthTiltDeg({}, flight.imu, 9.81).has_value());
}

}  // namespace
}  // namespace vio::tools
