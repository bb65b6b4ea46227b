#pragma once
// Rigs written wrong on purpose, the mistakes users make with their own data, so the tests and
// sweeps cover the estimator's physics checks (docs/bad-input.md): the IMU file in deg/s or in g,
// the cameras swapped. The calibration files stay right; only the measurements are written wrong.
#include <string>

#include "vio/dataset/euroc_dataset.h"

namespace vio::tools {

struct RigFaults {
  std::string gyro_units = "rad_s";  ///< imu0/data.csv's gyro columns: rad_s (right) or deg_s
  std::string accel_units = "m_s2";  ///< imu0/data.csv's accelerometer columns: m_s2 (right) or g
  bool swap_cameras = false;         ///< cam0's measurements written as cam1's and back
  bool any() const { return gyro_units != "rad_s" || accel_units != "m_s2" || swap_cameras; }
};

/// Throws std::invalid_argument naming the option for a unit that is not one of the choices.
void CheckRigFaults(const RigFaults& faults);

/// The IMU's units and the features' camera column (swap_cameras) of `dataset`, as written.
void ApplyRigFaults(const RigFaults& faults, EurocDataset* dataset);

}  // namespace vio::tools
