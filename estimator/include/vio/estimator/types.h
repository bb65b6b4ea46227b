#pragma once
// Basic value types shared by every library: time, typed ids, IMU samples,
// sensor calibration, and the one struct the front end hands the estimator.
//
// Conventions (written once, docs/design.md, "Conventions"):
//  * Timestamps are int64 nanoseconds (`Timestamp`), never floating seconds.
//  * `T_a_b` maps coordinates in frame b to frame a: p_a = T_a_b * p_b.
//  * Quaternions are Hamilton, Eigen storage order (x, y, z, w).
//  * w = world (z up, gravity (0, 0, -g)), b = body = IMU, c = camera.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace vio {

/// Time in integer nanoseconds since an arbitrary epoch.
using Timestamp = std::int64_t;

constexpr double NanosToSeconds(Timestamp t_ns) { return static_cast<double>(t_ns) * 1e-9; }
constexpr Timestamp SecondsToNanos(double t_s) {
  return static_cast<Timestamp>(t_s * 1e9 + (t_s >= 0 ? 0.5 : -0.5));
}

/// A strongly typed integer id: StateId and LandmarkId do not mix.
template <class Tag>
struct Id {
  std::int64_t value = -1;
  constexpr Id() = default;
  constexpr explicit Id(std::int64_t v) : value(v) {}
  constexpr bool valid() const { return value >= 0; }
  friend constexpr bool operator==(Id a, Id b) { return a.value == b.value; }
  friend constexpr bool operator!=(Id a, Id b) { return a.value != b.value; }
  friend constexpr bool operator<(Id a, Id b) { return a.value < b.value; }
};

using StateId = Id<struct StateIdTag>;        ///< one estimator state (one frame)
using LandmarkId = Id<struct LandmarkIdTag>;  ///< one 3D landmark / feature track

/// One IMU reading, in the IMU (= body) frame.
struct ImuSample {
  Timestamp t_ns = 0;
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();    ///< angular rate [rad/s]
  Eigen::Vector3d accel_m_s2 = Eigen::Vector3d::Zero();    ///< specific force [m/s^2]
};

/// IMU noise model (continuous-time densities, as in EuRoC imu0/sensor.yaml).
struct ImuCalibration {
  double rate_hz = 200.0;                  ///< nominal sample rate [Hz]
  double gyro_noise_density = 1.6968e-4;   ///< [rad/s/sqrt(Hz)]
  double gyro_random_walk = 1.9393e-5;     ///< [rad/s^2/sqrt(Hz)]
  double accel_noise_density = 2.0e-3;     ///< [m/s^2/sqrt(Hz)]
  double accel_random_walk = 3.0e-3;       ///< [m/s^3/sqrt(Hz)]
  Eigen::Isometry3d T_b_i = Eigen::Isometry3d::Identity();  ///< IMU in body (EuRoC: identity)
};

/// One camera as in EuRoC camN/sensor.yaml (pinhole + radial-tangential or
/// equidistant distortion).
struct CameraCalibration {
  int width = 752;                          ///< [px]
  int height = 480;                         ///< [px]
  double rate_hz = 20.0;                    ///< [Hz]
  Eigen::Vector4d intrinsics = Eigen::Vector4d(458.654, 457.296, 367.215, 248.375);  ///< fu fv cu cv [px]
  std::string distortion_model = "radial-tangential";  ///< or "equidistant"
  Eigen::Vector4d distortion = Eigen::Vector4d::Zero(); ///< k1 k2 p1 p2 (rad-tan) or k1..k4
  Eigen::Isometry3d T_b_c = Eigen::Isometry3d::Identity();  ///< camera in body (T_BS)
};

/// Rectified stereo geometry the estimator projects with (paper §5.4): both
/// rectified cameras share the pinhole (f, cx, cy); the right one sits at
/// +baseline along the left camera's x axis.
struct RectifiedStereo {
  double f = 450.0;         ///< focal length [px]
  double cx = 376.0;        ///< principal point x [px]
  double cy = 240.0;        ///< principal point y [px]
  double baseline = 0.11;   ///< [m], > 0
  Eigen::Isometry3d T_b_cl = Eigen::Isometry3d::Identity();  ///< rectified left camera in body
};

/// One landmark seen in both rectified images of a frame.
struct StereoObservation {
  LandmarkId landmark;
  Eigen::Vector3d z_px = Eigen::Vector3d::Zero();  ///< (u_L, u_R, v) rectified [px]
};

/// What the front end hands the estimator for one stereo frame.
struct StereoFrame {
  Timestamp t_ns = 0;
  std::vector<StereoObservation> observations;
};

}  // namespace vio

template <class Tag>
struct std::hash<vio::Id<Tag>> {
  std::size_t operator()(vio::Id<Tag> id) const noexcept { return std::hash<std::int64_t>()(id.value); }
};
