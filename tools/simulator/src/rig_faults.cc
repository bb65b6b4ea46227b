#include "vio/simulator/rig_faults.h"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <stdexcept>

namespace vio::tools {
namespace {

constexpr double kDegPerRad = 180.0 / M_PI;
constexpr double kStandardGravity = 9.80665;  // [m/s^2] per g

}  // namespace

void CheckRigFaults(const RigFaults& faults) {
  if (faults.gyro_units != "rad_s" && faults.gyro_units != "deg_s") {
    throw std::invalid_argument("--imu_gyro_units=" + faults.gyro_units + ": expected rad_s or deg_s");
  }
  if (faults.accel_units != "m_s2" && faults.accel_units != "g") {
    throw std::invalid_argument("--imu_accel_units=" + faults.accel_units + ": expected m_s2 or g");
  }
}

void ApplyRigFaults(const RigFaults& faults, EurocDataset* dataset) {
  CheckRigFaults(faults);
  const double gyro_scale = faults.gyro_units == "deg_s" ? kDegPerRad : 1.0;
  const double accel_scale = faults.accel_units == "g" ? 1.0 / kStandardGravity : 1.0;
  for (ImuSample& sample : dataset->imu) {
    sample.gyro_rad_s *= gyro_scale;
    sample.accel_m_s2 *= accel_scale;
  }
  if (!faults.swap_cameras) return;
  for (FeatureObservation& obs : dataset->features) obs.camera = 1 - obs.camera;
  std::sort(dataset->features.begin(), dataset->features.end(), [](const auto& a, const auto& b) {
    return std::tie(a.t_ns, a.camera, a.feature_id) < std::tie(b.t_ns, b.camera, b.feature_id);
  });
}

}  // namespace vio::tools
