// `vio simulate --noise_seed`: Monte Carlo realizations of one experiment.
// Different noise seeds keep the trajectory (ground truth) and the scene and
// change the IMU noise and the features; the same noise seed repeats them.
#include <gtest/gtest.h>

#include "vio/simulator/simulator.h"

namespace vio::tools {
namespace {

Simulation Simulate(std::uint64_t noise_seed) {
  SimulatorOptions options;
  options.duration_s = 5.0;
  options.noise_seed = noise_seed;
  return BuildSimulation(options);
}

TEST(SimulatorNoiseSeed, SameTrajectoryAndSceneOtherNoise) {
  const Simulation a = Simulate(1), b = Simulate(2), a_again = Simulate(1);
  ASSERT_EQ(a.dataset.groundtruth.size(), b.dataset.groundtruth.size());
  for (size_t i = 0; i < a.dataset.groundtruth.size(); ++i) {
    ASSERT_EQ(a.dataset.groundtruth[i].p_w_b, b.dataset.groundtruth[i].p_w_b) << i;
  }
  ASSERT_EQ(a.scene.landmarks.size(), b.scene.landmarks.size());
  for (size_t i = 0; i < a.scene.landmarks.size(); ++i) {
    ASSERT_EQ(a.scene.landmarks[i].p_w, b.scene.landmarks[i].p_w) << i;
  }
  ASSERT_EQ(a.dataset.imu.size(), b.dataset.imu.size());
  EXPECT_NE(a.dataset.imu[10].gyro_rad_s, b.dataset.imu[10].gyro_rad_s);
  EXPECT_EQ(a.dataset.imu[10].gyro_rad_s, a_again.dataset.imu[10].gyro_rad_s);
  ASSERT_FALSE(a.dataset.features.empty());
  ASSERT_EQ(a.dataset.features.size(), a_again.dataset.features.size());
}

}  // namespace
}  // namespace vio::tools
