// EuRoC sensor.yaml files (OpenCV FileStorage style: a `%YAML:1.0` first line):
//  camN/sensor.yaml: T_BS {rows: 4, cols: 4, data: [16, row-major]}, rate_hz,
//    resolution [w, h], camera_model pinhole, intrinsics [fu, fv, cu, cv],
//    distortion_model radial-tangential|equidistant, distortion_coefficients [4].
//  imu0/sensor.yaml: T_BS, rate_hz, gyroscope_noise_density,
//    gyroscope_random_walk, accelerometer_noise_density, accelerometer_random_walk.
// T_BS is the sensor frame S in the body frame B: p_B = T_BS * p_S.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "csv_reader.h"
#include "euroc_internal.h"
#include "text_writer.h"
#include "yaml_file.h"
#include "vio/dataset/euroc_dataset.h"

namespace vio::tools {
namespace {

/// Largest |R^T R - I| entry accepted for the rotation block of T_BS.
constexpr double kMaxRotationError = 1e-6;

bool IsKnownDistortionModel(const std::string& model) {
  return model == "radial-tangential" || model == "equidistant";
}

Eigen::Isometry3d ReadTBS(const YamlFile& file) {
  const YAML::Node node = file.Require(file.root(), "T_BS");
  const std::int64_t rows = file.Integer(file.Require(node, "rows"), "T_BS.rows");
  const std::int64_t cols = file.Integer(file.Require(node, "cols"), "T_BS.cols");
  const YAML::Node data = file.Require(node, "data");
  const std::size_t size = data.IsSequence() ? data.size() : 0;
  if (rows != 4 || cols != 4 || size != 16) {
    file.Fail(node, "T_BS must be 4x4 with 16 values, got rows " + std::to_string(rows) + ", cols " +
                   std::to_string(cols) + ", " + std::to_string(size) + " values");
  }
  const std::vector<double> values = file.Numbers(node, "data", 16);
  Eigen::Matrix4d T_b_s =
      Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(values.data());
  if (!T_b_s.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1), 1e-12)) {
    file.Fail(node, "T_BS last row must be [0, 0, 0, 1]");
  }
  const Eigen::Matrix3d R_b_s = T_b_s.topLeftCorner<3, 3>();
  const double rotation_error =
      (R_b_s.transpose() * R_b_s - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (rotation_error > kMaxRotationError) {
    file.Fail(node,
         "T_BS rotation is not orthonormal (|R^T R - I| = " + std::to_string(rotation_error) + ")");
  }
  T_b_s.row(3) << 0, 0, 0, 1;
  Eigen::Isometry3d isometry;
  isometry.matrix() = T_b_s;
  return isometry;
}

void CheckOptionalSensorType(const YamlFile& file, const std::string& expected) {
  const YAML::Node node = file.root()["sensor_type"];
  if (node.IsDefined() && node.IsScalar() && node.Scalar() != expected) {
    file.Fail(node, "sensor_type is '" + node.Scalar() + "', expected '" + expected + "'");
  }
}

void ReadResolution(const YamlFile& file, CameraCalibration* camera) {
  constexpr std::int64_t kMaxPixels = 1 << 20;  // per side
  const YAML::Node resolution = file.Require(file.root(), "resolution");
  if (!resolution.IsSequence() || resolution.size() != 2) {
    file.Fail(resolution, "'resolution' must be [width, height]");
  }
  const std::int64_t width = file.Integer(resolution[0], "resolution[0]");
  const std::int64_t height = file.Integer(resolution[1], "resolution[1]");
  if (width <= 0 || height <= 0 || width > kMaxPixels || height > kMaxPixels) {
    file.Fail(resolution, "'resolution' must be positive (and at most 2^20 px)");
  }
  camera->width = static_cast<int>(width);
  camera->height = static_cast<int>(height);
}

void AppendList(TextWriter& out, const double* values, int count) {
  out.Text("[");
  for (int i = 0; i < count; ++i) out.Text(i > 0 ? ", " : "").Real(values[i]);
  out.Text("]");
}

void AppendTBS(TextWriter& out, const Eigen::Isometry3d& T_b_s) {
  out.Text("# Sensor extrinsics wrt. the body-frame.\nT_BS:\n  cols: 4\n  rows: 4\n  data: [");
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      out.Real(T_b_s.matrix()(r, c)).Text(c < 3 ? ", " : (r < 3 ? ",\n         " : "]\n"));
    }
  }
}

}  // namespace

YAML::Node LoadSensorYaml(const std::string& path) {
  std::error_code ec;
  std::ifstream in(path, std::ios::binary);
  if (!std::filesystem::is_regular_file(path, ec) || !in) {
    throw DatasetError(path + ": cannot open (missing or not a file)");
  }
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (text.compare(0, 5, "%YAML") == 0) text.erase(0, text.find('\n'));
  try {
    return YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw LineError(path, e.mark.is_null() ? 1 : e.mark.line + 1, "YAML error: " + e.msg);
  }
}

CameraCalibration ReadCameraYaml(const std::string& path) {
  const YamlFile file(path);
  const YAML::Node& root = file.root();
  CheckOptionalSensorType(file, "camera");
  CameraCalibration camera;
  camera.T_b_c = ReadTBS(file);
  camera.rate_hz = file.Positive(root, "rate_hz");
  ReadResolution(file, &camera);
  if (const std::string model = file.String(root, "camera_model"); model != "pinhole") {
    file.Fail(root["camera_model"], "unknown camera_model '" + model + "' (supported: pinhole)");
  }
  const std::vector<double> intrinsics = file.Numbers(root, "intrinsics", 4);
  camera.intrinsics = Eigen::Vector4d(intrinsics.data());
  if (!(camera.intrinsics[0] > 0.0 && camera.intrinsics[1] > 0.0)) {
    file.Fail(root["intrinsics"], "'intrinsics' focal lengths fu, fv must be positive");
  }
  camera.distortion_model = file.String(root, "distortion_model");
  if (!IsKnownDistortionModel(camera.distortion_model)) {
    file.Fail(root["distortion_model"], "unknown distortion_model '" + camera.distortion_model +
                                            "' (supported: radial-tangential, equidistant)");
  }
  const std::vector<double> distortion = file.Numbers(root, "distortion_coefficients", 4);
  camera.distortion = Eigen::Vector4d(distortion.data());
  return camera;
}

void WriteCameraYaml(const CameraCalibration& camera, const std::string& path) {
  if (!IsKnownDistortionModel(camera.distortion_model)) {
    throw DatasetError(path + ": cannot write unknown distortion_model '" +
                       camera.distortion_model + "'");
  }
  TextWriter out(path);
  out.Text(
      "%YAML:1.0\n# General sensor definitions.\nsensor_type: camera\ncomment: written by vio\n\n");
  AppendTBS(out, camera.T_b_c);
  out.Text("\n# Camera specific definitions.\nrate_hz: ").Real(camera.rate_hz);
  out.Text("\nresolution: [").Int(camera.width).Text(", ").Int(camera.height);
  out.Text("]\ncamera_model: pinhole\nintrinsics: ");
  AppendList(out, camera.intrinsics.data(), 4);
  out.Text(" #fu, fv, cu, cv\ndistortion_model: ").Text(camera.distortion_model);
  out.Text("\ndistortion_coefficients: ");
  AppendList(out, camera.distortion.data(), 4);
  out.Text("\n");
  out.Save();
}

ImuCalibration ReadImuYaml(const std::string& path) {
  const YamlFile file(path);
  const YAML::Node& root = file.root();
  CheckOptionalSensorType(file, "imu");
  ImuCalibration imu;
  imu.T_b_i = ReadTBS(file);
  imu.rate_hz = file.Positive(root, "rate_hz");
  imu.gyro_noise_density = file.Positive(root, "gyroscope_noise_density");
  imu.gyro_random_walk = file.Positive(root, "gyroscope_random_walk");
  imu.accel_noise_density = file.Positive(root, "accelerometer_noise_density");
  imu.accel_random_walk = file.Positive(root, "accelerometer_random_walk");
  return imu;
}

void WriteImuYaml(const ImuCalibration& imu, const std::string& path) {
  TextWriter out(path);
  out.Text(
      "%YAML:1.0\n# General sensor definitions.\nsensor_type: imu\ncomment: written by vio\n\n");
  AppendTBS(out, imu.T_b_i);
  out.Text("rate_hz: ").Real(imu.rate_hz);
  out.Text("\n\n# inertial sensor noise model parameters (static)\ngyroscope_noise_density: ");
  out.Real(imu.gyro_noise_density).Text("  # [ rad / s / sqrt(Hz) ]\ngyroscope_random_walk: ");
  out.Real(imu.gyro_random_walk)
      .Text("  # [ rad / s^2 / sqrt(Hz) ]\naccelerometer_noise_density: ");
  out.Real(imu.accel_noise_density).Text("  # [ m / s^2 / sqrt(Hz) ]\naccelerometer_random_walk: ");
  out.Real(imu.accel_random_walk).Text("  # [ m / s^3 / sqrt(Hz) ]\n");
  out.Save();
}

void WriteBodyYaml(const std::string& path) {
  TextWriter out(path);
  out.Text("%YAML:1.0\ncomment: written by vio\n");
  out.Save();
}

void WriteGroundTruthSensorYaml(const std::string& path) {
  TextWriter out(path);
  out.Text(
      "%YAML:1.0\n# General sensor definitions.\nsensor_type: visual-inertial\n"
      "comment: ground truth of the body (IMU) frame, written by vio\n\n");
  AppendTBS(out, Eigen::Isometry3d::Identity());
  out.Save();
}

}  // namespace vio::tools
