// The rig checks (rig_checks.h): each rule on values that pass and values that must not, with the
// cause it names.
#include "vio/estimator/rig_checks.h"
#include "vio/estimator/so3.h"

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace vio {
namespace {

constexpr double kDegPerRad = 180.0 / M_PI;

bool Says(const std::string& problem, const std::string& what) { return problem.find(what) != std::string::npos; }

TEST(RigChecks, LimitsFollowTheNoiseFiguresAboveTheirFloors) {
  const RigLimits euroc = RigLimitsFor(ImuCalibration{}, 9.81);
  EXPECT_DOUBLE_EQ(euroc.max_gyro_bias_rad_s, kMinGyroBiasBound);
  EXPECT_DOUBLE_EQ(euroc.max_accel_bias_m_s2, kMinAccelBiasBound);
  ImuCalibration noisy;
  noisy.gyro_noise_density = 1e-3;
  noisy.accel_noise_density = 1e-2;
  const RigLimits limits = RigLimitsFor(noisy, 9.81);
  EXPECT_DOUBLE_EQ(limits.max_gyro_bias_rad_s, kGyroBiasPerNoise * 1e-3);
  EXPECT_DOUBLE_EQ(limits.max_accel_bias_m_s2, kAccelBiasPerNoise * 1e-2);
}

TEST(RigChecks, GravityAtRest) {
  const RigLimits limits = RigLimitsFor(ImuCalibration{}, 9.81);
  const Eigen::Vector3d gyro(0.01, -0.02, 0.005);
  const Eigen::Vector3d down = Eigen::Vector3d(0.3, -0.2, 1.0).normalized();
  EXPECT_EQ(CheckAtRest(9.81 * down, gyro, limits), "");
  EXPECT_EQ(CheckAtRest(9.81 * down + Eigen::Vector3d(0.8, 0.5, -0.6), gyro, limits), "");  // large biases
  EXPECT_TRUE(Says(CheckAtRest(1.0 * down, gyro, limits), "accelerometer in g?"));
  EXPECT_TRUE(Says(CheckAtRest(1000.0 * down, gyro, limits), "accelerometer in mg?"));
  EXPECT_TRUE(Says(CheckAtRest(4.0 * down, gyro, limits), "check the accelerometer's units and scale"));
  EXPECT_TRUE(Says(CheckAtRest(9.81 * down, kDegPerRad * gyro, limits), "gyro in deg/s?"));
}

TEST(RigChecks, BiasesAndFreeGravity) {
  const RigLimits limits = RigLimitsFor(ImuCalibration{}, 9.81);
  EXPECT_EQ(CheckBiases(Eigen::Vector3d(0.1, 0, 0), Eigen::Vector3d(0.5, 0.5, 0), limits, "x"), "");
  EXPECT_TRUE(Says(CheckBiases(Eigen::Vector3d(4.8, 0, 0), Eigen::Vector3d::Zero(), limits, "x"), "gyro in deg/s?"));
  EXPECT_TRUE(Says(CheckBiases(Eigen::Vector3d(40, 0, 0), Eigen::Vector3d::Zero(), limits, "x"), "units and scale"));
  EXPECT_TRUE(Says(CheckBiases(Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 2, 0), limits, "x"), "accelerometer bias"));
  for (double norm : {0.0, 7.5, 9.81, 12.0}) EXPECT_EQ(CheckFreeGravity(norm, limits), "") << norm;
  EXPECT_TRUE(Says(CheckFreeGravity(1.3, limits), "accelerometer in g?"));
  EXPECT_TRUE(Says(CheckFreeGravity(980, limits), "accelerometer in mg?"));
}

TEST(RigChecks, IntegratedGyroIsTheTrapezoidalSumOverTheInterval) {
  std::vector<ImuSample> imu;
  for (int i = 0; i <= 20; ++i) imu.push_back({i * 5'000'000LL, Eigen::Vector3d(1.0, -2.0, 0.5 * i), {}});
  // Over [12.5 ms, 52.5 ms]: x and y constant, z linear in time (0.5 per 5 ms).
  const Eigen::Vector3d sum = IntegratedGyro(imu, 12'500'000, 52'500'000);
  EXPECT_NEAR(sum.x(), 0.04, 1e-12);
  EXPECT_NEAR(sum.y(), -0.08, 1e-12);
  EXPECT_NEAR(sum.z(), 0.13, 1e-12);  // 0.04 s at the mean rate 3.25
}

TEST(RigChecks, IntegratedRotationComposesTheRatesOverTheInterval) {
  std::vector<ImuSample> imu;
  const Eigen::Vector3d rate(1.0, -2.0, 0.5);
  for (int i = 0; i <= 200; ++i) imu.push_back({i * 5'000'000LL, rate, {}});
  // A constant rate: the rotation about it by rate * 0.9 s, to rounding.
  const Eigen::Quaterniond q = IntegratedRotation(imu, 12'500'000, 912'500'000);
  EXPECT_LT(so3::Log(Eigen::Quaterniond(q * so3::ExpQuaternion(-0.9 * rate))).norm(), 1e-12);
  // A rate turning about another axis: the composition is not the summed vector's rotation.
  for (int i = 0; i <= 200; ++i) imu[i].gyro_rad_s = Eigen::Vector3d(1.0, 0.0, 0.01 * i);
  const Eigen::Quaterniond turning = IntegratedRotation(imu, 0, 1'000'000'000);
  const Eigen::Vector3d summed = IntegratedGyro(imu, 0, 1'000'000'000);
  EXPECT_GT(so3::Log(Eigen::Quaterniond(turning * so3::ExpQuaternion(-summed))).norm(), 1e-3);
}

// Rotation vectors of frame pairs, 0.1-0.3 rad each: `gyro` maps the camera's to the gyro's.
template <class Gyro>
RotationCheck Judge(Gyro gyro, double camera_scale = 1.0) {
  std::mt19937 rng(3);
  std::normal_distribution<double> normal(0.0, 1.0);
  RotationCheck check;
  for (int k = 0; k < 200 && !check.decided(); ++k) {
    const Eigen::Vector3d camera =
        camera_scale * (0.1 + 0.2 * (k % 5) / 4.0) * Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
    check.Add(gyro(camera, rng), camera);
  }
  return check;
}

TEST(RigChecks, GyroAgainstCameraRotation) {
  std::normal_distribution<double> noise(0.0, 0.01);
  const auto right = [&](const Eigen::Vector3d& c, std::mt19937& rng) {
    return Eigen::Vector3d(c + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
  };
  const RotationCheck ok = Judge(right);
  ASSERT_TRUE(ok.decided());
  EXPECT_EQ(ok.problem(), "");
  EXPECT_NEAR(ok.scale(), 1.0, 0.05);
  EXPECT_GT(ok.correlation(), 0.95);
  EXPECT_GE(ok.pairs(), RotationCheck::kDecisionPairs);

  const RotationCheck degrees = Judge([&](const Eigen::Vector3d& c, std::mt19937& rng) { return Eigen::Vector3d(kDegPerRad * right(c, rng)); });
  EXPECT_TRUE(Says(degrees.problem(), "gyro in deg/s?")) << degrees.problem();
  EXPECT_TRUE(Says(degrees.problem(), "x the camera's rotation over")) << degrees.problem();

  const RotationCheck twice = Judge([&](const Eigen::Vector3d& c, std::mt19937& rng) { return Eigen::Vector3d(right(c, rng) / kDegPerRad); });
  EXPECT_TRUE(Says(twice.problem(), "converted from degrees once more")) << twice.problem();

  std::normal_distribution<double> unrelated(0.0, 0.15);
  const RotationCheck apart = Judge([&](const Eigen::Vector3d&, std::mt19937& rng) {
    return Eigen::Vector3d(unrelated(rng), unrelated(rng), unrelated(rng));
  });
  EXPECT_TRUE(Says(apart.problem(), "are the camera and IMU clocks far apart")) << apart.problem();

  const RotationCheck scaled = Judge([&](const Eigen::Vector3d& c, std::mt19937& rng) { return Eigen::Vector3d(3.0 * right(c, rng)); });
  EXPECT_TRUE(Says(scaled.problem(), "check the gyro's units and scale")) << scaled.problem();
}

TEST(RigChecks, ARigAtRestIsNotJudged) {
  // Stereo rotation noise alone (below kMinPairRotationRad) never decides, whatever the gyro says.
  const RotationCheck rest = Judge([](const Eigen::Vector3d&, std::mt19937&) { return Eigen::Vector3d(0.5, 0, 0); },
                                   0.9 * RotationCheck::kMinPairRotationRad / 0.3);
  EXPECT_FALSE(rest.decided());
  EXPECT_EQ(rest.pairs(), 0);
}

}  // namespace
}  // namespace vio
