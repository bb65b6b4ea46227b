#pragma once
// Rig errors the simulator writes on purpose, as users' rigs have them: the
// cameras simulated with the true rig, the dataset written with
//  * a camera-IMU time offset: an image taken at IMU time t is stamped
//    t + time_offset (cam0/cam1 data.csv and features0 stamps); in the
//    estimator's convention, an image stamped t was taken at IMU time
//    t - offset;
//  * an extrinsic error: both cameras' T_BS in sensor.yaml moved rigidly in
//    the body, T_b_c written = E * T_b_c true with E a rotation of
//    extrinsic_error_deg about an axis and a translation of
//    extrinsic_error_m along a direction (the stereo baseline is kept).
#include <cstdint>
#include <optional>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "vio/dataset/euroc_dataset.h"

namespace vio::tools {

struct RigErrorOptions {
  double time_offset_ms = 0.0;       ///< camera stamps minus the true IMU time of the image [ms]
  double extrinsic_error_deg = 0.0;  ///< rotation of the written rig against the true one [deg], >= 0
  double extrinsic_error_m = 0.0;    ///< translation of the written rig against the true one [m], >= 0
  /// Rotation axis and translation direction (normalized); unset: drawn from the seed.
  std::optional<Eigen::Vector3d> rotation_axis;
  std::optional<Eigen::Vector3d> translation_direction;

  bool any() const { return time_offset_ms != 0.0 || extrinsic_error_deg != 0.0 || extrinsic_error_m != 0.0; }
};

/// Throws std::invalid_argument naming the flag when out of range (|offset| <= 10 s, rotation <= 90 deg,
/// translation <= 1 m, directions non-zero and finite).
void CheckRigErrorOptions(const RigErrorOptions& options);

/// E, the written rig in the true one's body: T_b_c written = E * T_b_c true. Unset directions are
/// uniform on the sphere from their own stream of `seed` (other draws do not move).
Eigen::Isometry3d ExtrinsicError(const RigErrorOptions& options, std::uint64_t seed);

/// Applies the errors to a dataset about to be written: camera and feature stamps shifted, both
/// cameras' T_b_c moved by ExtrinsicError. IMU and ground truth (the IMU clock) are untouched.
void ApplyRigErrors(const RigErrorOptions& options, std::uint64_t seed, EurocDataset* dataset);

/// Writes the errors as the truth an estimated calibration is compared with (`vio sweep` reads it):
/// YAML `time_offset_ms` (the estimator's convention) and the written rig's error E
/// (`extrinsic_rotation_deg`, `extrinsic_rotation_axis`, `extrinsic_translation_m` [x, y, z]); zeros for
/// a right rig. Throws std::runtime_error when the file cannot be written.
void WriteRigTruth(const RigErrorOptions& options, std::uint64_t seed, const std::string& path);

}  // namespace vio::tools
