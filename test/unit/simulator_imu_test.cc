// Synthesized IMU: integrating noise-free samples reproduces the trajectory;
// noise and bias random walk have the EuRoC discrete-time statistics.
#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "vio/simulator/imu.h"

namespace vio::tools {
namespace {

constexpr double kGravity = 9.81;

struct NavState {
  Eigen::Quaterniond q_w_b;
  Eigen::Vector3d v_w_b, p_w_b;
};

struct NavDerivative {
  Eigen::Vector4d q_dot;  // (x, y, z, w)
  Eigen::Vector3d v_dot, p_dot;
};

// q' = 1/2 q (x) (0, omega), v' = R a + g, p' = v
NavDerivative Derivative(const NavState& s, const ImuSample& m) {
  const Eigen::Quaterniond omega(0.0, m.gyro_rad_s.x(), m.gyro_rad_s.y(), m.gyro_rad_s.z());
  NavDerivative d;
  d.q_dot = 0.5 * (s.q_w_b * omega).coeffs();
  d.v_dot = s.q_w_b.toRotationMatrix() * m.accel_m_s2 + Eigen::Vector3d(0.0, 0.0, -kGravity);
  d.p_dot = s.v_w_b;
  return d;
}

NavState Step(const NavState& s, const NavDerivative& d, double h) {
  NavState out;
  out.q_w_b.coeffs() = s.q_w_b.coeffs() + h * d.q_dot;
  out.v_w_b = s.v_w_b + h * d.v_dot;
  out.p_w_b = s.p_w_b + h * d.p_dot;
  return out;
}

// Classic RK4 over [t_k, t_k+2] with the sample at t_k+1 as the midpoint.
NavState Rk4(const NavState& s, const ImuSample& m0, const ImuSample& m1, const ImuSample& m2, double h) {
  const NavDerivative k1 = Derivative(s, m0);
  const NavDerivative k2 = Derivative(Step(s, k1, h / 2), m1);
  const NavDerivative k3 = Derivative(Step(s, k2, h / 2), m1);
  const NavDerivative k4 = Derivative(Step(s, k3, h), m2);
  NavState out;
  out.q_w_b.coeffs() = s.q_w_b.coeffs() + h / 6 * (k1.q_dot + 2 * k2.q_dot + 2 * k3.q_dot + k4.q_dot);
  out.q_w_b.normalize();
  out.v_w_b = s.v_w_b + h / 6 * (k1.v_dot + 2 * k2.v_dot + 2 * k3.v_dot + k4.v_dot);
  out.p_w_b = s.p_w_b + h / 6 * (k1.p_dot + 2 * k2.p_dot + 2 * k3.p_dot + k4.p_dot);
  return out;
}

ImuSynthesisOptions NoiseFree() {
  ImuSynthesisOptions options;
  options.noise_scale = 0.0;
  options.initial_gyro_bias_sigma_rad_s = 0.0;
  options.initial_accel_bias_sigma_m_s2 = 0.0;
  options.gravity_m_s2 = kGravity;
  return options;
}

TEST(SynthesizeImuTest, IntegratingNoiseFreeSamplesStaysWithinOneMillimetreOverTenSeconds) {
  SyntheticTrajectoryOptions flight;
  flight.static_duration_s = 1.0;  // most of the 10 s in motion
  const SyntheticTrajectory trajectory(flight);
  std::mt19937_64 rng(3);
  const ImuSynthesis imu = SynthesizeImu(trajectory, 0, 10.0, NoiseFree(), &rng);
  ASSERT_EQ(imu.imu.size(), 2001u);
  const GroundTruthState& first = imu.groundtruth.front();
  NavState s{first.q_w_b, first.v_w_b, first.p_w_b};
  const double h = 2.0 / 200.0;
  for (std::size_t k = 0; k + 2 < imu.imu.size(); k += 2) {
    s = Rk4(s, imu.imu[k], imu.imu[k + 1], imu.imu[k + 2], h);
  }
  const GroundTruthState& last = imu.groundtruth.back();
  EXPECT_LT((s.p_w_b - last.p_w_b).norm(), 1e-3);
  EXPECT_LT((s.v_w_b - last.v_w_b).norm(), 1e-3);
  EXPECT_LT(s.q_w_b.angularDistance(last.q_w_b), 1e-5);
  double farthest_m = 0.0;  // the flight really moved
  for (const GroundTruthState& g : imu.groundtruth) farthest_m = std::max(farthest_m, (g.p_w_b - first.p_w_b).norm());
  EXPECT_GT(farthest_m, 2.0);
}

TEST(SynthesizeImuTest, StaticSamplesMeasureGravityPlusBias) {
  const SyntheticTrajectory trajectory{SyntheticTrajectoryOptions()};
  std::mt19937_64 rng(5);
  const ImuSynthesis imu = SynthesizeImu(trajectory, 42, 1.0, NoiseFree(), &rng);
  EXPECT_EQ(imu.imu.front().t_ns, 42);
  EXPECT_EQ(imu.imu[1].t_ns, 42 + 5'000'000);
  const Eigen::Matrix3d R_w_b = imu.groundtruth.front().q_w_b.toRotationMatrix();
  for (const ImuSample& m : imu.imu) {
    EXPECT_LT(m.gyro_rad_s.norm(), 1e-15);
    EXPECT_LT((m.accel_m_s2 - R_w_b.transpose() * Eigen::Vector3d(0, 0, kGravity)).norm(), 1e-12);
  }
}

TEST(SynthesizeImuTest, NoiseAndRandomWalkHaveEurocDiscreteSigmas) {
  const SyntheticTrajectory trajectory{SyntheticTrajectoryOptions()};
  ImuSynthesisOptions options;  // EuRoC densities
  options.initial_gyro_bias_sigma_rad_s = 0.0;
  options.initial_accel_bias_sigma_m_s2 = 0.0;
  std::mt19937_64 rng(9);
  const ImuSynthesis imu = SynthesizeImu(trajectory, 0, 2.9, options, &rng);  // static part
  double gyro_sq = 0.0, walk_sq = 0.0;
  int n = 0;
  for (std::size_t k = 0; k + 1 < imu.imu.size(); ++k) {
    const Eigen::Vector3d noise = imu.imu[k].gyro_rad_s - imu.groundtruth[k].gyro_bias;
    gyro_sq += noise.squaredNorm();
    walk_sq += (imu.groundtruth[k + 1].accel_bias - imu.groundtruth[k].accel_bias).squaredNorm();
    n += 3;
  }
  const double rate = options.calibration.rate_hz;
  EXPECT_NEAR(std::sqrt(gyro_sq / n), options.calibration.gyro_noise_density * std::sqrt(rate),
              0.05 * options.calibration.gyro_noise_density * std::sqrt(rate));
  EXPECT_NEAR(std::sqrt(walk_sq / n), options.calibration.accel_random_walk / std::sqrt(rate),
              0.05 * options.calibration.accel_random_walk / std::sqrt(rate));
}

TEST(SynthesizeImuTest, RejectsBadArguments) {
  const SyntheticTrajectory trajectory{SyntheticTrajectoryOptions()};
  std::mt19937_64 rng(1);
  EXPECT_THROW(SynthesizeImu(trajectory, 0, 0.0, ImuSynthesisOptions(), &rng), std::invalid_argument);
  ImuSynthesisOptions bad;
  bad.noise_scale = -1.0;
  EXPECT_THROW(SynthesizeImu(trajectory, 0, 1.0, bad, &rng), std::invalid_argument);
}

}  // namespace
}  // namespace vio::tools
