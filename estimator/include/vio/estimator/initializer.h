#pragma once
// The first state of a run: from IMU stillness (gravity from the mean
// accelerometer, gyro bias from the mean gyro) or given (ground truth).
#include <optional>
#include <string>
#include <vector>

#include "vio/estimator/estimator_options.h"
#include "vio/estimator/types.h"

namespace vio {

struct InitialState {
  Timestamp t_ns = 0;
  Eigen::Vector3d p_w_b = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_w_b = Eigen::Quaterniond::Identity();
  Eigen::Vector3d v_w_b = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();
};

/// A static initialization, or why there is none.
struct StaticInitResult {
  std::optional<InitialState> state;
  std::string reason;  ///< set when `state` is empty
  /// Set when `state` is empty because the IMU moves; a start of the data
  /// with too few samples yet to judge is the normal case, and not this.
  bool moving = false;
  /// The accelerometer's mean over the still window, when `state` is set (rig_checks.h) [m/s^2].
  Eigen::Vector3d accel_mean = Eigen::Vector3d::Zero();
};

/// Looks at the IMU in [t_ns - static_window_s, t_ns]: when it is still
/// (gyro and accel standard deviations below the options' bounds) returns the
/// state at t_ns with roll/pitch from gravity (the smallest rotation taking
/// the mean accelerometer to +z; yaw is unobservable), position and velocity 0,
/// gyro bias = mean gyro, accel bias 0.
StaticInitResult InitializeStatic(const std::vector<ImuSample>& imu, Timestamp t_ns, const InitOptions& options);

}  // namespace vio
