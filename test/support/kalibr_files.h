#pragma once
// Kalibr's calibration files written from a calibration, for the tests of the Kalibr reader and of
// `vio run --calibration=camchain-imucam.yaml` (header only).
#include <array>
#include <iomanip>
#include <sstream>
#include <string>

#include "vio/estimator/types.h"

namespace vio::test {

inline std::string KalibrRows(const Eigen::Isometry3d& T) {
  std::ostringstream os;
  os << std::setprecision(17);
  for (int r = 0; r < 4; ++r) {
    os << "  - [";
    for (int c = 0; c < 4; ++c) os << (c ? ", " : "") << T.matrix()(r, c);
    os << "]\n";
  }
  return os.str();
}

inline std::string KalibrList(const Eigen::Vector4d& v) {
  std::ostringstream os;
  os << std::setprecision(17) << "[" << v[0] << ", " << v[1] << ", " << v[2] << ", " << v[3] << "]";
  return os.str();
}

/// camchain-imucam.yaml as Kalibr writes it (radtan cameras; IMU frame = body): per camera T_cam_imu
/// (cam1 also T_cn_cnm1, times `chain_error`), the model, distortion, intrinsics, resolution and
/// timeshift_cam_imu = shift_s.
inline std::string KalibrCamchain(const std::array<CameraCalibration, 2>& cameras, double shift_s,
                                  const Eigen::Isometry3d& chain_error = Eigen::Isometry3d::Identity()) {
  std::ostringstream os;
  os << std::setprecision(17);
  for (int i = 0; i < 2; ++i) {
    const CameraCalibration& cam = cameras[i];
    os << "cam" << i << ":\n  T_cam_imu:\n" << KalibrRows(cam.T_b_c.inverse());
    if (i == 1) os << "  T_cn_cnm1:\n" << KalibrRows(chain_error * cam.T_b_c.inverse() * cameras[0].T_b_c);
    os << "  cam_overlaps: [" << 1 - i << "]\n  camera_model: pinhole\n  distortion_coeffs: "
       << KalibrList(cam.distortion) << "\n  distortion_model: radtan\n  intrinsics: " << KalibrList(cam.intrinsics)
       << "\n  resolution: [" << cam.width << ", " << cam.height << "]\n  rostopic: /cam" << i
       << "/image_raw\n  timeshift_cam_imu: " << shift_s << "\n";
  }
  return os.str();
}

/// imu.yaml as a Kalibr user writes it (EuRoC's IMU noise figures by default).
inline std::string KalibrImuYaml(const ImuCalibration& imu = ImuCalibration{}) {
  std::ostringstream os;
  os << std::setprecision(17) << "#Accelerometers\naccelerometer_noise_density: " << imu.accel_noise_density
     << "\naccelerometer_random_walk: " << imu.accel_random_walk << "\n#Gyroscopes\ngyroscope_noise_density: "
     << imu.gyro_noise_density << "\ngyroscope_random_walk: " << imu.gyro_random_walk
     << "\nrostopic: /imu0\nupdate_rate: " << imu.rate_hz << "\n";
  return os.str();
}

}  // namespace vio::test
