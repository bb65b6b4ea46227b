#include "vio/simulator/imu.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace vio::tools {
namespace {

Eigen::Vector3d GaussianVector(double sigma, std::mt19937_64* rng) {
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Vector3d out;
  for (int i = 0; i < 3; ++i) out[i] = sigma * normal(*rng);  // fixed draw order: x, y, z
  return out;
}

void CheckOptions(const ImuSynthesisOptions& options, double duration_s) {
  if (!(options.calibration.rate_hz > 0.0) || !(duration_s > 0.0) || !(options.noise_scale >= 0.0)) {
    throw std::invalid_argument("IMU synthesis: need rate > 0 (got " +
                                std::to_string(options.calibration.rate_hz) + " Hz), duration > 0 (got " +
                                std::to_string(duration_s) + " s) and noise scale >= 0");
  }
}

}  // namespace

ImuSynthesis SynthesizeImu(const SyntheticTrajectory& trajectory, Timestamp start_ns, double duration_s,
                           const ImuSynthesisOptions& options, std::mt19937_64* rng) {
  CheckOptions(options, duration_s);
  const ImuCalibration& calib = options.calibration;
  const Timestamp period_ns = SecondsToNanos(1.0 / calib.rate_hz);
  const double dt = NanosToSeconds(period_ns);
  const double s = options.noise_scale;
  const double gyro_white = s * calib.gyro_noise_density / std::sqrt(dt);
  const double accel_white = s * calib.accel_noise_density / std::sqrt(dt);
  const double gyro_walk = s * calib.gyro_random_walk * std::sqrt(dt);
  const double accel_walk = s * calib.accel_random_walk * std::sqrt(dt);
  const Eigen::Vector3d g_w(0.0, 0.0, -options.gravity_m_s2);

  Eigen::Vector3d gyro_bias = GaussianVector(options.initial_gyro_bias_sigma_rad_s, rng);
  Eigen::Vector3d accel_bias = GaussianVector(options.initial_accel_bias_sigma_m_s2, rng);
  ImuSynthesis out;
  const Timestamp duration_ns = SecondsToNanos(duration_s);
  for (Timestamp offset_ns = 0; offset_ns <= duration_ns; offset_ns += period_ns) {
    const KinematicState state = trajectory.Evaluate(NanosToSeconds(offset_ns));
    const Eigen::Matrix3d R_w_b = state.q_w_b.toRotationMatrix();
    ImuSample sample;
    sample.t_ns = start_ns + offset_ns;
    sample.gyro_rad_s = state.omega_b + gyro_bias + GaussianVector(gyro_white, rng);
    sample.accel_m_s2 = R_w_b.transpose() * (state.a_w_b - g_w) + accel_bias + GaussianVector(accel_white, rng);
    out.imu.push_back(sample);
    out.groundtruth.push_back(
        {sample.t_ns, state.p_w_b, state.q_w_b, state.v_w_b, gyro_bias, accel_bias});
    gyro_bias += GaussianVector(gyro_walk, rng);
    accel_bias += GaussianVector(accel_walk, rng);
  }
  return out;
}

}  // namespace vio::tools
