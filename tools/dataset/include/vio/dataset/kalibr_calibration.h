#pragma once
// Kalibr's calibration files (github.com/ethz-asl/kalibr), the file most users' calibration ends in:
//   camchain-imucam.yaml: cam0, cam1 with T_cam_imu (4x4 list of rows: camera from IMU), camera_model
//     pinhole, intrinsics [fu, fv, cu, cv], distortion_model radtan | equidistant,
//     distortion_coeffs [4], resolution [w, h], timeshift_cam_imu [s] (t_imu = t_cam + shift), and
//     for cam1 T_cn_cnm1 (cam1 from cam0, checked against the two T_cam_imu);
//   imu.yaml: accelerometer_noise_density, accelerometer_random_walk, gyroscope_noise_density,
//     gyroscope_random_walk, update_rate, at the top level or under imu0 (Kalibr's results file).
// The IMU frame is the body frame: T_BS of camera i = T_cam_imu^-1. Errors name the file and line.
#include <array>
#include <string>

#include "vio/dataset/euroc_dataset.h"

namespace vio::tools {

struct KalibrCalibration {
  std::array<CameraCalibration, 2> cameras;
  ImuCalibration imu;
  Timestamp camera_time_offset_ns = 0;  ///< -timeshift_cam_imu (EurocDataset::camera_time_offset_ns)
};

/// True when `path` names a file (a camchain), not a folder (an ASL folder's sensor.yaml files).
bool IsCalibrationFile(const std::string& path);

/// The IMU file beside a camchain: imu.yaml, or imu-NAME.yaml for camchain-imucam-NAME.yaml (Kalibr's
/// results); throws DatasetError naming both when neither exists.
std::string KalibrImuFileBeside(const std::string& camchain_path);

/// Reads both files. Throws DatasetError "<file>:<line>: <what>".
KalibrCalibration ReadKalibr(const std::string& camchain_path, const std::string& imu_path);

}  // namespace vio::tools
