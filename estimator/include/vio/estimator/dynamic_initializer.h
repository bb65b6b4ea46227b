#pragma once
// Dynamic initialization: the first state from a moving start, from a short
// window of stereo frames and the IMU between them (docs/initialization.md).
//   1. stereo motion: each frame's body pose in the first frame's body, metric
//      (stereo_motion.h: 3D-3D fits of consecutive frames' stereo points);
//   2. visual-inertial alignment (inertial_alignment.h): gyro bias from the
//      rotations, then velocities, gravity (|g| fixed) and accel bias (under
//      its prior) linearly from the preintegrated delta-v / delta-p;
//   3. refinement: a visual-inertial bundle adjustment of the window (the
//      project's own Window: IMU factors, stereo factors, Gauss-Newton), whose
//      information gives the newest state's covariance: the prior handed to the
//      estimator, with position and yaw (unobservable) held as the gauge.
// It returns nothing, with the reason, when the window does not determine
// the state: too few frames or IMU, too few landmarks with stereo depth
// tracked between frames, stereo and IMU inconsistent, or a gravity direction
// or velocity less certain than the options' bounds.
#include <optional>
#include <string>
#include <vector>

#include "vio/estimator/estimator_options.h"
#include "vio/estimator/initializer.h"
#include "vio/estimator/window.h"

namespace vio {

struct DynamicInitResult {
  std::optional<InitialState> state;  ///< the newest frame's state (world: z up, origin and yaw of the first frame)
  /// Its prior for the estimator's window over [dp (world), dtheta (body), v, b_g, b_a]: the
  /// refinement's covariance with its correlations (tilt and accel bias are strongly correlated), but
  /// position and yaw, the new run's gauge, at the options' first-pose sigmas and uncorrelated.
  Eigen::Matrix<double, 15, 15> prior_covariance = Eigen::Matrix<double, 15, 15>::Identity();
  StatePrior prior;  ///< the same, marginals only (speed/bias diagonal), for reports
  /// Marginal covariance of the newest state from the refinement, over
  /// [dp (world), dtheta (body), v, b_g, b_a] (window_covariance.h).
  Eigen::Matrix<double, 15, 15> covariance = Eigen::Matrix<double, 15, 15>::Zero();
  std::string reason;  ///< set when `state` is empty
  /// |g| of the visual-inertial alignment with gravity free, once it ran [m/s^2] (0 before).
  double free_gravity_norm = 0;
  /// The refinement's estimates of the window's earlier frames (time order).
  std::vector<InitialState> earlier;
};

/// Initializes from `frames` (time order; the caller chooses the window) and `imu`, which must cover
/// them. calibration: the IMU noise the estimator uses.
DynamicInitResult InitializeDynamic(const std::vector<StereoFrame>& frames, const std::vector<ImuSample>& imu,
                                    const ImuCalibration& calibration, const RectifiedStereo& stereo,
                                    const EstimatorOptions& options);

/// How far the image moved over `frames` [px]: the largest, over the frames, of the median left-image
/// displacement of the landmarks they share with the first (nothing when none shares min_landmarks).
/// Auto initialization takes a static start only when the camera agrees that the IMU is still (a rig
/// gliding at constant velocity has a still IMU too).
std::optional<double> CameraPixelMotion(const std::vector<StereoFrame>& frames, int min_landmarks);

}  // namespace vio
