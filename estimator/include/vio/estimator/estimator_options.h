#pragma once
// Options of the estimator (back end): the policy, its window, the solver, the
// measurement model and the initialization. Defaults in class; one doc line
// per field with units. `Visit` lists every field once for the YAML file and
// the command-line flags (see tools/options_registry.h).
#include <string>
#include <vector>

namespace vio {

/// Which policy over build / Gauss-Newton / marginalize runs (paper ch. 4).
struct PolicyOptions {
  std::string policy = "swf";   ///< the estimator policy
  int window_size = 10;         ///< states kept in the window [frames]
  /// What happens to landmarks seen by the state that leaves an SWF window.
  std::string swf_landmarks = "marginalize";

  template <class V>
  void Visit(V& v) {
    v("policy", policy, "estimator policy", {"swf"});
    v("window_size", window_size, "states kept in the sliding window [frames]");
    v("swf_landmarks", swf_landmarks,
      "SWF: landmarks seen by the leaving state are kept (paper-exact, prior over them) "
      "or marginalized with it (prior over states only, faster)",
      {"keep", "marginalize"});
  }
};

/// Gauss-Newton through Ceres.
struct SolverOptions {
  int max_iterations = 3;         ///< Gauss-Newton iterations per frame [count]
  double max_solver_time_s = 0.05;  ///< wall-time bound per solve [s]
  double function_tolerance = 1e-6;  ///< relative cost decrease that counts as converged []
  int num_threads = 1;            ///< Ceres threads [count]

  template <class V>
  void Visit(V& v) {
    v("max_iterations", max_iterations, "Gauss-Newton iterations per frame [count]");
    v("max_solver_time_s", max_solver_time_s, "wall-time bound of one solve [s]");
    v("function_tolerance", function_tolerance, "relative cost decrease that counts as converged []");
    v("num_threads", num_threads, "Ceres threads [count]");
  }
};

/// Measurement models and their noise.
struct ModelOptions {
  double pixel_sigma = 0.5;        ///< stereo measurement noise, each of (u_L, u_R, v) [px]
  double huber_px = 1.5;           ///< Huber loss threshold in whitened units [sigma]; 0 = none
  double gravity = 9.81;           ///< gravity magnitude, world -z [m/s^2]
  double imu_noise_scale = 5.0;    ///< multiplies the IMU noise densities of sensor.yaml []
  double min_disparity_px = 1.0;   ///< new landmarks need at least this stereo disparity [px]
  double max_depth_m = 30.0;       ///< new landmarks beyond this depth are not added [m]
  double reintegrate_bias_threshold = 0.01;  ///< re-preintegrate when the gyro bias moved [rad/s]

  template <class V>
  void Visit(V& v) {
    v("pixel_sigma", pixel_sigma, "stereo measurement noise of each of (u_L, u_R, v) [px]");
    v("huber_px", huber_px, "Huber loss threshold on whitened residuals [sigma]; 0 disables it");
    v("gravity", gravity, "gravity magnitude along world -z [m/s^2]");
    v("imu_noise_scale", imu_noise_scale, "factor on the IMU noise densities of sensor.yaml []");
    v("min_disparity_px", min_disparity_px, "smallest stereo disparity of a new landmark [px]");
    v("max_depth_m", max_depth_m, "largest depth of a new landmark [m]");
    v("reintegrate_bias_threshold", reintegrate_bias_threshold,
      "gyro-bias change that triggers re-preintegration [rad/s]");
  }
};

/// How the first state is found.
struct InitOptions {
  std::string init = "static";          ///< static (IMU stillness) or groundtruth
  double static_window_s = 1.0;         ///< IMU span averaged for gravity and gyro bias [s]
  double static_max_gyro_std = 0.05;    ///< stillness: largest gyro standard deviation [rad/s]
  double static_max_accel_std = 0.8;    ///< stillness: largest accel standard deviation [m/s^2]
  double prior_position_sigma = 1e-3;   ///< first-pose prior on position [m]
  double prior_yaw_sigma = 1e-3;        ///< first-pose prior on yaw [rad]
  double prior_tilt_sigma = 0.02;       ///< first-pose prior on roll and pitch [rad]
  double prior_velocity_sigma = 0.05;   ///< first-state prior on velocity [m/s]
  double prior_gyro_bias_sigma = 0.01;  ///< first-state prior on the gyro bias [rad/s]
  double prior_accel_bias_sigma = 0.2;  ///< first-state prior on the accel bias [m/s^2]

  template <class V>
  void Visit(V& v) {
    v("init", init, "initialization: static (IMU stillness) or groundtruth", {"static", "groundtruth"});
    v("static_window_s", static_window_s, "IMU span averaged for gravity and gyro bias [s]");
    v("static_max_gyro_std", static_max_gyro_std, "stillness: largest gyro standard deviation [rad/s]");
    v("static_max_accel_std", static_max_accel_std, "stillness: largest accel standard deviation [m/s^2]");
    v("prior_position_sigma", prior_position_sigma, "first-pose prior on position [m]");
    v("prior_yaw_sigma", prior_yaw_sigma, "first-pose prior on yaw [rad]");
    v("prior_tilt_sigma", prior_tilt_sigma, "first-pose prior on roll and pitch [rad]");
    v("prior_velocity_sigma", prior_velocity_sigma, "first-state prior on velocity [m/s]");
    v("prior_gyro_bias_sigma", prior_gyro_bias_sigma, "first-state prior on the gyro bias [rad/s]");
    v("prior_accel_bias_sigma", prior_accel_bias_sigma, "first-state prior on the accel bias [m/s^2]");
  }
};

/// Everything the estimator is configured with.
struct EstimatorOptions {
  PolicyOptions policy;
  SolverOptions solver;
  ModelOptions model;
  InitOptions init;
};

}  // namespace vio
