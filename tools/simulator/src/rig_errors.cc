#include "vio/simulator/rig_errors.h"

#include <cmath>
#include <fstream>
#include <random>
#include <stdexcept>
#include <string>

namespace vio::tools {
namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Vector3d UnitFrom(const std::optional<Eigen::Vector3d>& given, std::mt19937_64* rng) {
  if (given) return given->normalized();
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::Vector3d v;
  do {
    v = Eigen::Vector3d(normal(*rng), normal(*rng), normal(*rng));
  } while (v.norm() < 1e-6);
  return v.normalized();
}

void CheckDirection(const std::optional<Eigen::Vector3d>& direction, const std::string& flag) {
  if (direction && (!direction->allFinite() || direction->norm() < 1e-9)) {
    throw std::invalid_argument("--" + flag + ": expected a non-zero finite vector x,y,z");
  }
}

}  // namespace

void CheckRigErrorOptions(const RigErrorOptions& options) {
  if (!std::isfinite(options.time_offset_ms) || std::abs(options.time_offset_ms) > 10000.0) {
    throw std::invalid_argument("--time_offset_ms: expected a finite offset within +-10000 ms, got " +
                                std::to_string(options.time_offset_ms));
  }
  if (!(options.extrinsic_error_deg >= 0.0 && options.extrinsic_error_deg <= 90.0)) {
    throw std::invalid_argument("--extrinsic_error_deg: expected 0..90 deg, got " +
                                std::to_string(options.extrinsic_error_deg));
  }
  if (!(options.extrinsic_error_m >= 0.0 && options.extrinsic_error_m <= 1.0)) {
    throw std::invalid_argument("--extrinsic_error_m: expected 0..1 m, got " + std::to_string(options.extrinsic_error_m));
  }
  CheckDirection(options.rotation_axis, "extrinsic_error_axis");
  CheckDirection(options.translation_direction, "extrinsic_error_direction");
}

Eigen::Isometry3d ExtrinsicError(const RigErrorOptions& options, std::uint64_t seed) {
  std::mt19937_64 rng(seed ^ 0x7269676572720000ULL);  // own stream
  const Eigen::Vector3d axis = UnitFrom(options.rotation_axis, &rng);
  const Eigen::Vector3d direction = UnitFrom(options.translation_direction, &rng);
  Eigen::Isometry3d E = Eigen::Isometry3d::Identity();
  E.linear() = Eigen::AngleAxisd(options.extrinsic_error_deg * kPi / 180.0, axis).toRotationMatrix();
  E.translation() = options.extrinsic_error_m * direction;
  return E;
}

void ApplyRigErrors(const RigErrorOptions& options, std::uint64_t seed, EurocDataset* dataset) {
  const Timestamp shift_ns = SecondsToNanos(1e-3 * options.time_offset_ms);
  for (std::vector<CameraFrame>& rows : dataset->frames) {
    for (CameraFrame& row : rows) row.t_ns += shift_ns;
  }
  for (FeatureObservation& observation : dataset->features) observation.t_ns += shift_ns;
  if (options.extrinsic_error_deg == 0.0 && options.extrinsic_error_m == 0.0) return;
  const Eigen::Isometry3d E = ExtrinsicError(options, seed);
  for (CameraCalibration& camera : dataset->cameras) camera.T_b_c = E * camera.T_b_c;
}

void WriteRigTruth(const RigErrorOptions& options, std::uint64_t seed, const std::string& path) {
  const Eigen::Isometry3d E = ExtrinsicError(options, seed);
  const Eigen::AngleAxisd rotation(E.linear());
  const Eigen::Vector3d axis = rotation.angle() > 0.0 ? rotation.axis() : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d t = E.translation();
  std::ofstream out(path);
  out.precision(17);
  out << "# vio simulate: the rig errors this dataset was written with, the truth for an estimated calibration\n"
      << "time_offset_ms: " << options.time_offset_ms << "  # an image stamped t was taken at IMU time t - offset\n"
      << "# T_b_c in sensor.yaml = E * T_b_c true; E's rotation and translation (body frame)\n"
      << "extrinsic_rotation_deg: " << rotation.angle() * 180.0 / kPi << "\n"
      << "extrinsic_rotation_axis: [" << axis.x() << ", " << axis.y() << ", " << axis.z() << "]\n"
      << "extrinsic_translation_m: [" << t.x() << ", " << t.y() << ", " << t.z() << "]\n";
  if (!out) throw std::runtime_error(path + ": cannot write");
}

}  // namespace vio::tools
