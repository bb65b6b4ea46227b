#include "vio/dataset/kalibr_calibration.h"

#include <cmath>
#include <filesystem>

#include "yaml_file.h"

namespace vio::tools {
namespace {

namespace fs = std::filesystem;

/// Largest |R^T R - I| entry accepted for a rotation.
constexpr double kMaxKalibrRotationError = 1e-6;
/// T_cn_cnm1 must agree with the two T_cam_imu to this (Kalibr writes both from one estimate).
constexpr double kMaxChainTranslationError = 1e-3;  // [m]
constexpr double kMaxChainRotationError = 1e-3;     // [rad]

// A 4x4 rigid transform written as a list of four rows.
Eigen::Isometry3d ReadRigid(const YamlFile& file, const YAML::Node& map, const std::string& key) {
  const YAML::Node node = file.Require(map, key);
  if (!node.IsSequence() || node.size() != 4) file.Fail(node, "'" + key + "' must be 4 rows of 4 numbers");
  Eigen::Matrix4d T;
  for (std::size_t r = 0; r < 4; ++r) {
    if (!node[r].IsSequence() || node[r].size() != 4) {
      file.Fail(node[r].IsDefined() ? node[r] : node, "'" + key + "' row " + std::to_string(r) + " must be 4 numbers");
    }
    for (std::size_t c = 0; c < 4; ++c) {
      T(static_cast<int>(r), static_cast<int>(c)) =
          file.Number(node[r][c], key + "[" + std::to_string(r) + "][" + std::to_string(c) + "]");
    }
  }
  if (!T.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1), 1e-12)) file.Fail(node, "'" + key + "' last row must be [0, 0, 0, 1]");
  const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
  const double error = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (error > kMaxKalibrRotationError || R.determinant() < 0) {
    file.Fail(node, "'" + key + "' rotation is not a rotation (|R^T R - I| = " + std::to_string(error) + ")");
  }
  T.row(3) << 0, 0, 0, 1;
  Eigen::Isometry3d isometry;
  isometry.matrix() = T;
  return isometry;
}

std::string DistortionModel(const YamlFile& file, const YAML::Node& camera) {
  const std::string model = file.String(camera, "distortion_model");
  if (model == "radtan") return "radial-tangential";
  if (model == "equidistant") return "equidistant";
  file.Fail(camera["distortion_model"], "unknown distortion_model '" + model + "' (supported: radtan, equidistant)");
}

CameraCalibration ReadCamera(const YamlFile& file, const std::string& name, double* timeshift_s) {
  const YAML::Node camera = file.Require(file.root(), name);
  if (!camera.IsMap()) file.Fail(camera, "'" + name + "' must be a map of keys");
  CameraCalibration out;
  out.T_b_c = ReadRigid(file, camera, "T_cam_imu").inverse();
  if (const std::string model = file.String(camera, "camera_model"); model != "pinhole") {
    file.Fail(camera["camera_model"], "unknown camera_model '" + model + "' (supported: pinhole)");
  }
  const std::vector<double> intrinsics = file.Numbers(camera, "intrinsics", 4);
  out.intrinsics = Eigen::Vector4d(intrinsics.data());
  if (!(out.intrinsics[0] > 0.0 && out.intrinsics[1] > 0.0)) {
    file.Fail(camera["intrinsics"], "'intrinsics' focal lengths fu, fv must be positive");
  }
  out.distortion_model = DistortionModel(file, camera);
  const std::vector<double> distortion = file.Numbers(camera, "distortion_coeffs", 4);
  out.distortion = Eigen::Vector4d(distortion.data());
  const std::vector<double> resolution = file.Numbers(camera, "resolution", 2);
  if (!(resolution[0] >= 1 && resolution[1] >= 1 && resolution[0] <= (1 << 20) && resolution[1] <= (1 << 20)) ||
      resolution[0] != std::floor(resolution[0]) || resolution[1] != std::floor(resolution[1])) {
    file.Fail(camera["resolution"], "'resolution' must be [width, height], positive integers");
  }
  out.width = static_cast<int>(resolution[0]);
  out.height = static_cast<int>(resolution[1]);
  const YAML::Node shift = camera["timeshift_cam_imu"];
  *timeshift_s = shift.IsDefined() && !shift.IsNull() ? file.Number(shift, "timeshift_cam_imu") : 0.0;
  if (std::abs(*timeshift_s) > 10.0) file.Fail(shift, "'timeshift_cam_imu' beyond 10 s: is it in seconds?");
  return out;
}

// cam1's T_cn_cnm1 (cam1 from cam0), when given, must be the two T_cam_imu's.
void CheckChain(const YamlFile& file, const KalibrCalibration& calibration) {
  const YAML::Node cam1 = file.root()["cam1"];
  if (!cam1["T_cn_cnm1"].IsDefined()) return;
  const Eigen::Isometry3d given = ReadRigid(file, cam1, "T_cn_cnm1");
  const Eigen::Isometry3d implied = calibration.cameras[1].T_b_c.inverse() * calibration.cameras[0].T_b_c;
  const Eigen::Isometry3d difference = given.inverse() * implied;
  const double rotation = Eigen::AngleAxisd(difference.linear()).angle();
  if (difference.translation().norm() > kMaxChainTranslationError || rotation > kMaxChainRotationError) {
    file.Fail(cam1["T_cn_cnm1"], "'T_cn_cnm1' disagrees with the cameras' T_cam_imu by " +
                                     std::to_string(difference.translation().norm()) + " m and " +
                                     std::to_string(rotation) + " rad: the camchain is not one calibration");
  }
}

ImuCalibration ReadImu(const std::string& path) {
  const YamlFile file(path);
  const YAML::Node nested = file.root()["imu0"];  // Kalibr's results file: under imu0
  const YAML::Node root = nested.IsDefined() && nested.IsMap() ? nested : file.root();
  ImuCalibration imu;
  imu.rate_hz = file.Positive(root, "update_rate");
  imu.gyro_noise_density = file.Positive(root, "gyroscope_noise_density");
  imu.gyro_random_walk = file.Positive(root, "gyroscope_random_walk");
  imu.accel_noise_density = file.Positive(root, "accelerometer_noise_density");
  imu.accel_random_walk = file.Positive(root, "accelerometer_random_walk");
  return imu;
}

}  // namespace

bool IsCalibrationFile(const std::string& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

std::string KalibrImuFileBeside(const std::string& camchain_path) {
  const fs::path camchain(camchain_path);
  const fs::path plain = camchain.parent_path() / "imu.yaml";
  std::error_code ec;
  if (fs::is_regular_file(plain, ec)) return plain.string();
  const std::string name = camchain.filename().string();
  const std::string prefix = "camchain-imucam-";
  if (name.rfind(prefix, 0) == 0) {
    const fs::path results = camchain.parent_path() / ("imu-" + name.substr(prefix.size()));
    if (fs::is_regular_file(results, ec)) return results.string();
    throw DatasetError(camchain_path + ": no IMU calibration beside it (" + plain.string() + " or " +
                       results.string() + "): give it with --calibration_imu");
  }
  throw DatasetError(camchain_path + ": no IMU calibration beside it (" + plain.string() +
                     "): give it with --calibration_imu");
}

KalibrCalibration ReadKalibr(const std::string& camchain_path, const std::string& imu_path) {
  const YamlFile file(camchain_path);
  KalibrCalibration calibration;
  double shift0 = 0, shift1 = 0;
  calibration.cameras[0] = ReadCamera(file, "cam0", &shift0);
  calibration.cameras[1] = ReadCamera(file, "cam1", &shift1);
  if (std::abs(shift1 - shift0) > 1e-4) {
    file.Fail(file.root()["cam1"]["timeshift_cam_imu"],
              "cam0 and cam1 have different timeshift_cam_imu (" + std::to_string(shift0) + " and " +
                  std::to_string(shift1) + " s): a stereo pair needs one clock");
  }
  calibration.camera_time_offset_ns = -SecondsToNanos(shift0);
  CheckChain(file, calibration);
  calibration.imu = ReadImu(imu_path);
  return calibration;
}

}  // namespace vio::tools
