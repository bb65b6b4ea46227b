#pragma once
// Short names for the rows of the preintegrated IMU state/residual
// [dtheta, dv, dp, b_g, b_a] (ImuPreintegration's offsets), shared by
// imu_preintegration.cc and imu_factor.cc.
#include "vio/estimator/imu_preintegration.h"

namespace vio::imu_state_index {

inline constexpr int kR = ImuPreintegration::kRotation;
inline constexpr int kV = ImuPreintegration::kVelocity;
inline constexpr int kP = ImuPreintegration::kPosition;
inline constexpr int kBg = ImuPreintegration::kBiasGyro;
inline constexpr int kBa = ImuPreintegration::kBiasAccel;

}  // namespace vio::imu_state_index
