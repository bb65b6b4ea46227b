#pragma once
// The state `--init=groundtruth` starts the estimator from.
//
// EuRoC's state_groundtruth_estimate0/data.csv carries the whole state
// (pose, velocity, biases); TUM text carries the pose only. For a pose-only
// ground truth the rest is derived from the poses and the IMU, with central
// differences of step h over the samples t_i in the averaging span:
//   v_w_b(t)   = (p(t + h) - p(t - h)) / 2h
//   gyro_bias  = mean_i [ w_i - Log(R(t_i - h)^T R(t_i + h)) / 2h ]
//   accel_bias = mean_i [ a_i - R(t_i)^T (p''(t_i) + g e_z) ],
//                p''(t) = (p(t + h) - 2 p(t) + p(t - h)) / h^2
// (world z up, gravity g along -z, so a resting IMU measures +g e_z).
#include <optional>
#include <vector>

#include "vio/estimator/initializer.h"
#include "vio/dataset/euroc_dataset.h"

namespace vio::tools {

/// The ground truth interpolated at t_ns (linear in position, velocity and
/// biases, slerp in rotation); nullopt outside the ground-truth span.
std::optional<GroundTruthState> InterpolateGroundTruth(const std::vector<GroundTruthState>& gt, Timestamp t_ns);

/// The initial state at t_ns. Velocity and biases come from `gt` when it has
/// them, else they are derived as above from the IMU samples within
/// `span_s` of t_ns (either side); nullopt outside the ground-truth span.
std::optional<InitialState> GroundTruthInitialState(const std::vector<GroundTruthState>& gt,
                                                    const std::vector<ImuSample>& imu, Timestamp t_ns,
                                                    double gravity_m_s2, double span_s);

/// Largest tilt of the ground truth's world z axis from up for which pos+yaw
/// alignment (which keeps roll and pitch) is valid [deg].
constexpr double kMaxPosYawTiltDeg = 5.0;

/// Angle between the ground truth's world z axis and up as the IMU measures it
/// (specific force rotated into the ground-truth world, minus the ground
/// truth's own acceleration, averaged) [deg]; nullopt without overlap.
std::optional<double> GroundTruthTiltDeg(const std::vector<GroundTruthState>& gt, const std::vector<ImuSample>& imu,
                                         double gravity_m_s2);

}  // namespace vio::tools
