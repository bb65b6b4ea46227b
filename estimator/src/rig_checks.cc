#include "vio/estimator/rig_checks.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include <glog/logging.h>

#include "vio/estimator/so3.h"

namespace vio {
namespace {

constexpr double kDegPerRad = 180.0 / M_PI;
constexpr double kStandardGravity = 9.80665;  // [m/s^2] per g
// A measured ratio names a unit mistake when within this fraction of the unit's factor.
constexpr double kUnitTolerance = 0.25;

bool Near(double value, double target) { return std::abs(value / target - 1.0) <= kUnitTolerance; }
// The dynamic alignment's free gravity is rough (half a second of motion, the accel bias under a
// prior): within a factor of 2 of a unit's gravity names that unit.
bool WithinFactorTwo(double value, double target) { return value >= 0.5 * target && value <= 2.0 * target; }

std::string Fixed(double value, int digits) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(digits) << value;
  return os.str();
}

}  // namespace

RigLimits RigLimitsFor(const ImuCalibration& calibration, double gravity) {
  RigLimits limits;
  limits.gravity = gravity;
  limits.max_gyro_bias_rad_s = std::max(kMinGyroBiasBound, kGyroBiasPerNoise * calibration.gyro_noise_density);
  limits.max_accel_bias_m_s2 = std::max(kMinAccelBiasBound, kAccelBiasPerNoise * calibration.accel_noise_density);
  return limits;
}

std::string CheckAtRest(const Eigen::Vector3d& accel_mean, const Eigen::Vector3d& gyro_mean, const RigLimits& limits) {
  const double norm = accel_mean.norm();
  if (std::abs(norm - limits.gravity) > 2 * limits.max_accel_bias_m_s2) {
    std::ostringstream why;
    why << "the accelerometer reads " << Fixed(norm, 3) << " m/s^2 at rest, gravity is " << limits.gravity
        << " m/s^2 (at most " << 2 * limits.max_accel_bias_m_s2 << " off with the biases the IMU's noise allows)";
    if (Near(norm, limits.gravity / kStandardGravity)) {
      why << ": is imu0/data.csv's accelerometer in g? It must be in m/s^2 (multiply by 9.80665)";
    } else if (Near(norm, 1000 * limits.gravity / kStandardGravity)) {
      why << ": is imu0/data.csv's accelerometer in mg? It must be in m/s^2";
    } else {
      why << ": check the accelerometer's units and scale in imu0/data.csv (m/s^2)";
    }
    return why.str();
  }
  return CheckBiases(gyro_mean, Eigen::Vector3d::Zero(), limits, "the gyro at rest");
}

std::string CheckBiases(const Eigen::Vector3d& gyro_bias, const Eigen::Vector3d& accel_bias, const RigLimits& limits,
                        const std::string& who) {
  std::ostringstream why;
  if (gyro_bias.norm() > limits.max_gyro_bias_rad_s) {
    why << who << ": gyro bias " << Fixed(gyro_bias.norm(), 3) << " rad/s, beyond the plausible "
        << limits.max_gyro_bias_rad_s << " rad/s for the IMU's noise figures";
    if (gyro_bias.norm() / kDegPerRad <= limits.max_gyro_bias_rad_s) {
      why << ": is imu0/data.csv's gyro in deg/s? It must be in rad/s (multiply by 0.0174533)";
    } else {
      why << ": check the gyro's units and scale in imu0/data.csv (rad/s)";
    }
  } else if (accel_bias.norm() > limits.max_accel_bias_m_s2) {
    why << who << ": accelerometer bias " << Fixed(accel_bias.norm(), 3) << " m/s^2, beyond the plausible "
        << limits.max_accel_bias_m_s2 << " m/s^2 for the IMU's noise figures: check the accelerometer's units and "
        << "scale in imu0/data.csv (m/s^2) and the camera-IMU calibration";
  }
  return why.str();
}

namespace {

// Calls visit(mean rate [rad/s], dt [s]) for each IMU interval's part within [t0, t1], in order.
template <typename Visit>
void ForEachGyroInterval(const std::vector<ImuSample>& imu, Timestamp t0_ns, Timestamp t1_ns, Visit visit) {
  const auto first = std::lower_bound(imu.begin(), imu.end(), t0_ns,
                                      [](const ImuSample& m, Timestamp t) { return m.t_ns < t; });
  for (auto i = static_cast<std::size_t>(std::max<std::ptrdiff_t>(1, first - imu.begin()));
       i < imu.size() && imu[i - 1].t_ns < t1_ns; ++i) {
    const Timestamp from = std::max(imu[i - 1].t_ns, t0_ns), to = std::min(imu[i].t_ns, t1_ns);
    if (to > from) visit(0.5 * (imu[i - 1].gyro_rad_s + imu[i].gyro_rad_s), NanosToSeconds(to - from));
  }
}

}  // namespace

Eigen::Vector3d IntegratedGyro(const std::vector<ImuSample>& imu, Timestamp t0_ns, Timestamp t1_ns) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  ForEachGyroInterval(imu, t0_ns, t1_ns, [&sum](const Eigen::Vector3d& rate, double dt) { sum += rate * dt; });
  return sum;
}

Eigen::Quaterniond IntegratedRotation(const std::vector<ImuSample>& imu, Timestamp t0_ns, Timestamp t1_ns) {
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  ForEachGyroInterval(imu, t0_ns, t1_ns,
                      [&q](const Eigen::Vector3d& rate, double dt) { q = q * so3::ExpQuaternion(rate * dt); });
  return q.normalized();
}

std::string CheckFreeGravity(double free_gravity_norm, const RigLimits& limits) {
  std::ostringstream why;
  const double g_units = limits.gravity / kStandardGravity;
  if (WithinFactorTwo(free_gravity_norm, g_units) || WithinFactorTwo(free_gravity_norm, 1000 * g_units)) {
    const bool milli = WithinFactorTwo(free_gravity_norm, 1000 * g_units);
    why << "the stereo motion and the accelerometer agree on a gravity of " << Fixed(free_gravity_norm, 3)
        << " m/s^2, not " << limits.gravity << ": is imu0/data.csv's accelerometer in " << (milli ? "mg" : "g")
        << "? It must be in m/s^2";
  }
  return why.str();
}

void RotationCheck::Add(const Eigen::Vector3d& theta_gyro, const Eigen::Vector3d& theta_camera) {
  if (decided_ || theta_camera.norm() < kMinPairRotationRad) return;
  gyro_dot_camera_ += theta_gyro.dot(theta_camera);
  camera_squared_ += theta_camera.squaredNorm();
  gyro_squared_ += theta_gyro.squaredNorm();
  camera_rotation_rad_ += theta_camera.norm();
  ++pairs_;
  if (camera_rotation_rad_ >= kDecisionRotationRad && pairs_ >= kDecisionPairs) Decide();
}

void RotationCheck::Decide() {
  decided_ = true;
  scale_ = gyro_dot_camera_ / camera_squared_;
  correlation_ = gyro_squared_ > 0 ? gyro_dot_camera_ / std::sqrt(camera_squared_ * gyro_squared_) : 0.0;
  std::ostringstream why;
  const std::string over = " over " + std::to_string(pairs_) + " frame pairs and " +
                           Fixed(camera_rotation_rad_, 2) + " rad of camera rotation";
  if (Near(scale_, kDegPerRad) && correlation_ >= kMinRotationCorrelation) {
    why << "the gyro reads " << Fixed(scale_, 1) << "x the camera's rotation" << over
        << ": is imu0/data.csv's gyro in deg/s? It must be in rad/s (multiply by 0.0174533)";
  } else if (Near(scale_, 1.0 / kDegPerRad) && correlation_ >= kMinRotationCorrelation) {
    why << "the gyro reads 1/" << Fixed(1.0 / scale_, 1) << " of the camera's rotation" << over
        << ": was imu0/data.csv's gyro, in rad/s, converted from degrees once more? It must be in rad/s";
  } else if (correlation_ < kMinRotationCorrelation) {
    why << "the gyro's rotation does not follow the camera's (correlation " << Fixed(correlation_, 2)
        << over << "): are the camera and IMU clocks far apart (a time offset of many frames; "
        << "timestamps in ns on one clock?), or is the camera's rotation in T_BS (cam0/sensor.yaml) wrong?";
  } else if (scale_ < kMinGyroScale || scale_ > kMaxGyroScale) {
    why << "the gyro reads " << Fixed(scale_, 3) << "x the camera's rotation" << over
        << ": check the gyro's units and scale in imu0/data.csv (rad/s)";
  }
  problem_ = why.str();
  LOG(INFO) << "rig check: gyro against camera rotation: scale " << Fixed(scale_, 3) << ", correlation "
            << Fixed(correlation_, 3) << over << (problem_.empty() ? ": consistent" : ": " + problem_);
}

}  // namespace vio
