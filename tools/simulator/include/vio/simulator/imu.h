#pragma once
// IMU measurements synthesized from an analytic trajectory.
//
// At each sample k (period dt = 1 / rate):
//   gyro_k  = omega_b(t_k) + b_g,k + n_g,     n_g ~ N(0, (sigma_g sqrt(rate))^2)
//   accel_k = R_w_b(t_k)^T (a_w(t_k) - g_w) + b_a,k + n_a,   g_w = (0, 0, -g)
//   b_k+1   = b_k + w,                          w ~ N(0, (sigma_rw sqrt(dt))^2)
// with the continuous-time densities sigma of ImuCalibration (EuRoC
// imu0/sensor.yaml). The ground truth (pose, velocity, both biases) is
// written at every sample.
#include <random>
#include <vector>

#include "vio/estimator/types.h"
#include "vio/dataset/euroc_dataset.h"
#include "vio/simulator/trajectory.h"

namespace vio::tools {

struct ImuSynthesisOptions {
  /// Sample rate and noise densities (defaults: EuRoC ADIS16448).
  ImuCalibration calibration;
  /// Multiplies every noise density and random walk (0 = noise-free, biases
  /// constant).
  double noise_scale = 1.0;
  /// Standard deviation of the initial gyro bias, per axis [rad/s].
  double initial_gyro_bias_sigma_rad_s = 0.01;
  /// Standard deviation of the initial accelerometer bias, per axis [m/s^2].
  double initial_accel_bias_sigma_m_s2 = 0.05;
  /// Gravity magnitude; world gravity is (0, 0, -g) [m/s^2].
  double gravity_m_s2 = 9.81;
};

struct ImuSynthesis {
  std::vector<ImuSample> imu;
  std::vector<GroundTruthState> groundtruth;  ///< one per IMU sample
};

/// Samples at start_ns + k * round(1e9 / rate) for every k with t <= duration.
/// Throws std::invalid_argument on a non-positive rate or duration or a
/// negative noise scale.
ImuSynthesis SynthesizeImu(const SyntheticTrajectory& trajectory, Timestamp start_ns, double duration_s,
                           const ImuSynthesisOptions& options, std::mt19937_64* rng);

}  // namespace vio::tools
