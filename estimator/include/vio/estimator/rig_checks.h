#pragma once
// Physics checks of a rig (docs/bad-input.md): what the initializers estimate and what the IMU
// measures against gravity, the IMU's noise figures and the stereo camera's own motion. A rig that
// cannot be right (the gyro in deg/s, the accelerometer in g, camera and IMU clocks seconds apart)
// is named with what to fix instead of giving a run that ends `ok` with a wrong result. Each check
// returns an empty string when the rig is plausible, else the problem and its likely cause.
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "vio/estimator/types.h"

namespace vio {

/// Bounds derived from the IMU's sensor.yaml noise figures (before imu_noise_scale):
///   |b_g| <= max(kMinGyroBiasBound, kGyroBiasPerNoise * gyroscope_noise_density)
///   |b_a| <= max(kMinAccelBiasBound, kAccelBiasPerNoise * accelerometer_noise_density)
/// The floors are the worst turn-on biases of consumer MEMS IMUs (20 deg/s, about 0.15 g); the
/// factors let a noisier IMU have proportionally larger biases (EuRoC's ADIS16448: 0.35 rad/s and
/// 1.5 m/s^2, 10-20 times its real biases).
struct RigLimits {
  double gravity = 9.81;              ///< [m/s^2]
  double max_gyro_bias_rad_s = 0.35;  ///< [rad/s]
  double max_accel_bias_m_s2 = 1.5;   ///< [m/s^2]
};
inline constexpr double kMinGyroBiasBound = 0.35;   // [rad/s] (20 deg/s)
inline constexpr double kGyroBiasPerNoise = 2000;   // [sqrt(Hz)]
inline constexpr double kMinAccelBiasBound = 1.5;   // [m/s^2]
inline constexpr double kAccelBiasPerNoise = 750;   // [sqrt(Hz)]
RigLimits RigLimitsFor(const ImuCalibration& calibration, double gravity);

/// The IMU at rest (static initialization): the accelerometer's mean norm must be gravity within
/// two accel-bias bounds, the gyro's mean (its bias) within its bound.
std::string CheckAtRest(const Eigen::Vector3d& accel_mean, const Eigen::Vector3d& gyro_mean, const RigLimits& limits);

/// An initializer's biases against the bounds; `who` names the initializer in the message.
std::string CheckBiases(const Eigen::Vector3d& gyro_bias, const Eigen::Vector3d& accel_bias, const RigLimits& limits,
                        const std::string& who);

/// The gyro's readings integrated over [t0_ns, t1_ns] as a vector (trapezoidal), not as a
/// rotation: to first order the rotation vector, and unlike a rotation it does not wrap when the gyro
/// reads 57 times too much.
Eigen::Vector3d IntegratedGyro(const std::vector<ImuSample>& imu, Timestamp t0_ns, Timestamp t1_ns);

/// The gyro's readings over [t0_ns, t1_ns] composed as a rotation R_t0_t1 (each sample interval
/// at its mean rate), for spans whose rotation vectors do not simply add.
Eigen::Quaterniond IntegratedRotation(const std::vector<ImuSample>& imu, Timestamp t0_ns, Timestamp t1_ns);

/// The dynamic initializer's free gravity (stereo motion aligned to the accelerometer): a norm near
/// gravity / 9.81 (or 1000 times that), within a factor of 2, is an accelerometer in g (or mg); other misfits are not
/// judged here (they are transient: the initializer waits).
std::string CheckFreeGravity(double free_gravity_norm, const RigLimits& limits);

/// Gyro rotation against stereo rotation over frame pairs kPairSpanS apart (a 3D-3D fit of one
/// frame's stereo points to the other's is noisy, about 0.02 rad at 0.5 px: the span makes the
/// rotation large against it). Pairs whose camera rotation is below kMinPairRotationRad are left
/// out (a rig at rest shows only that noise); the others are accumulated until the camera turned
/// kDecisionRotationRad over at least kDecisionPairs pairs, then judged once: the
/// least-squares scale s = sum(theta_g . theta_c) / sum(|theta_c|^2) and the correlation
/// rho = sum(theta_g . theta_c) / sqrt(sum |theta_g|^2 sum |theta_c|^2) of the rotation vectors
/// (both in the body frame). s near 57.3: the gyro is in deg/s; near 1/57.3: degrees converted twice;
/// rho < kMinRotationCorrelation: the rotations do not match in time or axes (camera/IMU clocks far
/// apart, or T_BS's rotation wrong); s outside [kMinGyroScale, kMaxGyroScale]: a wrong gyro scale.
class RotationCheck {
 public:
  static constexpr double kPairSpanS = 0.4;
  static constexpr double kMinPairRotationRad = 0.1;
  static constexpr double kDecisionRotationRad = 3.0;
  static constexpr int kDecisionPairs = 10;
  static constexpr double kMinRotationCorrelation = 0.5;
  static constexpr double kMinGyroScale = 0.5;
  static constexpr double kMaxGyroScale = 2.0;

  /// One frame pair: the gyro's and the camera's rotation vectors over it [rad].
  void Add(const Eigen::Vector3d& theta_gyro, const Eigen::Vector3d& theta_camera);
  bool decided() const { return decided_; }
  /// Set once decided and the rotations disagree.
  const std::string& problem() const { return problem_; }
  double scale() const { return scale_; }
  double correlation() const { return correlation_; }
  int pairs() const { return pairs_; }

 private:
  void Decide();

  double gyro_dot_camera_ = 0;
  double camera_squared_ = 0;
  double gyro_squared_ = 0;
  double camera_rotation_rad_ = 0;
  int pairs_ = 0;
  bool decided_ = false;
  double scale_ = 0;
  double correlation_ = 0;
  std::string problem_;
};

}  // namespace vio
