#pragma once
// Options of the estimator (back end): the policy, its window, the solver, the
// measurement model and the initialization. Defaults in class; one doc line
// per field with units. `Visit` lists every field once for the YAML file and
// the command-line flags (see tools/options_registry.h).
#include <string>
#include <vector>

#include "vio/estimator/option_range.h"

namespace vio {

/// Which policy over build / Gauss-Newton / marginalize runs (paper ch. 4).
struct PolicyOptions {
  std::string policy = "swf";   ///< the estimator policy
  int window_size = 10;         ///< states kept in the window [frames]
  /// What happens to landmarks seen by the state that leaves an SWF window.
  std::string swf_landmarks = "marginalize";
  /// What EKF-SLAM does with landmarks the newest frame did not observe.
  std::string ekf_landmarks = "marginalize_unseen";
  /// EKF-SLAM: most landmarks in the state; a frame's new landmarks enter
  /// while there is room (0: no limit) [count].
  int ekf_max_landmarks = 20;
  int keyframe_temporal_window = 3;  ///< keyframe policy: most recent frames always kept [frames]
  double keyframe_overlap = 0.7;     ///< keyframe policy: new keyframe below this shared-landmark fraction []
  /// Frames with fewer stereo observations are tracking loss: not used,
  /// propagated on the IMU (tracking_monitor.h) [count]. 1: every frame with
  /// something to track is used (better with exact simulated features, not
  /// with image front ends: docs/design.md, "The estimator, frame by frame").
  int min_frame_features = 10;

  template <class V>
  void Visit(V& v) {
    v("policy", policy,
      "estimator policy: swf (sliding window), msckf (MSCKF as optimization), ekf (EKF-SLAM: previous state "
      "marginalized before one GN step), iekf (iterated EKF: GN to convergence), fixed_lag (MSCKF "
      "marginalization, GN to convergence), keyframe (OKVIS-like), batch (no marginalization), smoother "
      "(incremental: every state kept, each frame the recent states and the older ones that moved solved)",
      {"swf", "msckf", "ekf", "iekf", "fixed_lag", "keyframe", "batch", "smoother"});
    v("window_size", window_size, "states kept in the sliding window [frames]", AtLeast(1));
    v("swf_landmarks", swf_landmarks,
      "SWF: landmarks seen by the leaving state are kept (paper-exact, prior over them) "
      "or marginalized with it (prior over states only, faster)",
      {"keep", "marginalize"});
    v("ekf_landmarks", ekf_landmarks,
      "ekf, iekf: every landmark stays in the state (keep, the paper's EKF-SLAM; cost grows with the map) or "
      "those the newest frame did not observe are marginalized after the update (marginalize_unseen, bounded)",
      {"keep", "marginalize_unseen"});
    v("ekf_max_landmarks", ekf_max_landmarks,
      "ekf, iekf: most landmarks in the state (the map); a frame's new landmarks enter, in the frame's order, "
      "while there is room; 0 = no limit (each step costs O(map^3)) [count]",
      AtLeast(0));
    v("keyframe_temporal_window", keyframe_temporal_window,
      "keyframe policy: the most recent frames, always kept [frames]", AtLeast(1));
    v("keyframe_overlap", keyframe_overlap,
      "keyframe policy: a frame sharing less than this fraction of its landmarks with the last keyframe "
      "becomes a keyframe []", Between(0, 1));
    v("min_frame_features", min_frame_features,
      "frames with fewer stereo observations count as tracking loss: their observations are not used and the "
      "state is propagated on the IMU, with a warning [count]",
      AtLeast(0));
  }
};

/// The MSCKF as optimization (paper Algorithm 4) and the fixed-lag smoother.
struct MsckfOptions {
  int msckf_gn_steps = 1;                 ///< Gauss-Newton steps per MSCKF update [count]
  int msckf_min_track_length = 2;         ///< observations a track needs to be used [frames]
  double msckf_max_reprojection = 5.0;    ///< triangulation: largest whitened reprojection error [sigma]
  /// The gate rises to this times the median error of the frame's tracks
  /// (drifted poses raise them all); 0 = msckf_max_reprojection alone.
  double msckf_gate_median_factor = 3.0;
  double msckf_max_landmark_sigma = 2.0;  ///< triangulation: largest position standard deviation [m]
  /// What a track seen from a leaving state contributes: whole_track (all its
  /// observations; the track restarts), leaving_views (paper Algorithm 4:
  /// only its views from the leaving states, when it was seen from all of
  /// them; the track goes on without them) or shared_views (its views from the
  /// leaving states when it was seen from at least two of them).
  std::string msckf_leaving_update = "shared_views";

  template <class V>
  void Visit(V& v) {
    v("msckf_gn_steps", msckf_gn_steps, "MSCKF: Gauss-Newton steps per update (fixed_lag: to convergence) [count]", AtLeast(1));
    v("msckf_leaving_update", msckf_leaving_update,
      "MSCKF: a track seen from a leaving state is used whole and restarts (whole_track), or gives only its views "
      "from the leaving states and goes on: when seen from all of them (leaving_views, paper Algorithm 4) or from "
      "at least two (shared_views: fewer views are lost with their state)",
      {"whole_track", "leaving_views", "shared_views"});
    v("msckf_min_track_length", msckf_min_track_length, "MSCKF: observations a track needs to be used [frames]", AtLeast(2));
    v("msckf_max_reprojection", msckf_max_reprojection,
      "MSCKF triangulation: largest whitened reprojection error [sigma]", Positive());
    v("msckf_gate_median_factor", msckf_gate_median_factor,
      "MSCKF: the reprojection gate rises to this times the median error of the frame's tracks (at least 5 of "
      "them) when larger, up to max_whitened_residual: poses that drifted through a tracking loss or dropped frames "
      "raise every track's error, a wrong association only its own; 0 = msckf_max_reprojection alone []",
      AtLeast(0));
    v("msckf_max_landmark_sigma", msckf_max_landmark_sigma,
      "MSCKF triangulation: largest landmark position standard deviation [m]", Positive());
  }
};

/// Long-lived landmarks of the windowed policies swf, msckf and fixed_lag
/// (persistent_landmarks.h): kept as parameters beyond the window.
struct PersistentOptions {
  int persistent_landmarks = 0;      ///< most landmarks kept beyond the window [count]; 0 = off
  int persistent_min_track = 5;      ///< observations a landmark needs before it is kept [count]
  double persistent_retire_s = 10.0; ///< a kept landmark not re-observed for this long is marginalized [s]

  template <class V>
  void Visit(V& v) {
    v("persistent_landmarks", persistent_landmarks,
      "swf, msckf, fixed_lag: most landmarks kept as parameters after their observing states leave (their "
      "information in the marginalization prior; re-observed ids re-attach); 0 = off [count]",
      Between(0, 1000));
    v("persistent_min_track", persistent_min_track,
      "observations a landmark needs before it is kept beyond the window [count]", AtLeast(2));
    v("persistent_retire_s", persistent_retire_s,
      "a kept landmark not re-observed for this long is marginalized into the prior [s]", Positive());
  }
};

/// The local map behind the windows swf and msckf (local_map.h): keyframes
/// and their landmarks kept live behind the recent frames.
struct LocalMapOptions {
  int local_map_keyframes = 0;     ///< K: keyframes solved with the recent window [count]; 0 = off
  double local_map_overlap = 0.7;  ///< new keyframe below this landmark fraction shared with the reference keyframe []
  double local_map_max_link_s = 3.0;  ///< longest IMU factor between keyframes, else the frame is one [s]
  double local_map_cull = 0.9;  ///< a parked keyframe goes when this fraction of its landmarks is seen by 4 others []

  template <class V>
  void Visit(V& v) {
    v("local_map_keyframes", local_map_keyframes,
      "swf, msckf: a local map behind the window: frames leaving it are keyframes (kept live with their landmarks, "
      "tied by IMU preintegration) or dropped; each solve frees the window plus the K keyframes sharing most "
      "landmarks with it, holds their neighbours fixed and parks the rest outside the cost; 0 = off [count]",
      Between(0, 200));
    v("local_map_overlap", local_map_overlap,
      "local map: a frame becomes a keyframe when less than this fraction of its landmarks is seen by its "
      "reference keyframe (the keyframe sharing most of them) []",
      Between(0, 1));
    v("local_map_max_link_s", local_map_max_link_s,
      "local map: a frame leaving the window joins the map as a keyframe when the IMU factor from the last keyframe "
      "would span more than this (a camera circling a mapped place adds no keyframes by overlap) [s]",
      Positive());
    v("local_map_cull", local_map_cull,
      "local map: a keyframe leaving the cost (not the first or the newest) is culled when at least this fraction of "
      "its landmarks is seen by 4 other keyframes (its IMU factors merge into one, the frames anchored on it follow "
      "the keyframe before it, its summaries the nearest parked keyframe seeing their landmark); 0 = never []",
      Between(0, 1));
  }
};

/// Full batch: no marginalization; old states frozen while running, all
/// solved together at the end.
struct BatchOptions {
  int batch_final_iterations = 20;  ///< Gauss-Newton iterations of the final full solve [count]
  int batch_solve_every = 5;        ///< while running, solve the recent states every this many frames [frames]

  template <class V>
  void Visit(V& v) {
    v("batch_final_iterations", batch_final_iterations,
      "batch: Gauss-Newton iterations of the final solve over every state and landmark [count]", AtLeast(1));
    v("batch_solve_every", batch_solve_every,
      "batch: while running, solve the recent states every this many frames (IMU prediction between) [frames]", AtLeast(1));
  }
};

/// The incremental smoother (smoother_policy.h): every state and landmark kept; each frame
/// the newest states and the older ones whose pending step is large are solved, the rest
/// held with their observations summarized per landmark.
struct SmootherOptions {
  int smoother_active_states = 10;             ///< newest tracked states solved every frame [frames]
  double smoother_relinearize_threshold = 1e-3;  ///< an older state's pending step that frees it [m or rad]
  int smoother_checks_per_frame = 4;           ///< older states whose pending step is checked per frame [count]
  int smoother_full_every = 0;                 ///< every this many frames every state is solved; 0 = never [frames]

  template <class V>
  void Visit(V& v) {
    v("smoother_active_states", smoother_active_states,
      "smoother: the newest states that observe landmarks, solved every frame with every later state (a tracking "
      "loss's IMU-only states stay solved until that many tracked frames follow them); the older ones are held "
      "unless freed [frames]",
      AtLeast(1));
    v("smoother_relinearize_threshold", smoother_relinearize_threshold,
      "smoother: an older state joins the frame's solve when its Gauss-Newton step alone (position [m] or "
      "rotation [rad]) exceeds this [m or rad]",
      AtLeast(0));
    v("smoother_checks_per_frame", smoother_checks_per_frame,
      "smoother: older states whose pending step is checked each frame, the newest held ones and then in turn "
      "from the oldest; 0 = every one [count]",
      AtLeast(0));
    v("smoother_full_every", smoother_full_every,
      "smoother: every this many frames every state is freed for the frame's solve (the whole problem "
      "relinearized, by sparse Cholesky); 0 = never [frames]",
      AtLeast(0));
  }
};

/// Gauss-Newton steps on the window (Ceres evaluates and, for lm, solves).
struct SolverOptions {
  /// gn: undamped Gauss-Newton, every step taken (the paper's step);
  /// lm: Ceres' Levenberg-Marquardt (trust region, steps may be rejected).
  std::string step = "gn";
  int max_iterations = 10;        ///< most steps of a to-convergence solve (a safety net) [count]
  double parameter_tolerance = 1e-8;  ///< gn: converged when |dx| <= this * (|x| + this) []
  double max_solver_time_s = 0.0;   ///< wall-time bound per solve [s]; 0 = none (a run that hits one is not reproducible)
  double function_tolerance = 1e-3;  ///< relative cost change that counts as converged []
  int num_threads = 1;            ///< Ceres threads [count]
  std::string linear_solver = "dense";  ///< dense | sparse (Schur-reduced) | sparse_full (whole system) | iterative

  template <class V>
  void Visit(V& v) {
    v("step", step,
      "gn: undamped Gauss-Newton steps, each taken (the paper's); lm: Ceres Levenberg-Marquardt (damped, may "
      "reject steps)",
      {"gn", "lm"});
    v("max_iterations", max_iterations,
      "most Gauss-Newton steps of a solve to convergence, a safety net (the criterion is function_tolerance / "
      "parameter_tolerance) [count]",
      AtLeast(1));
    v("parameter_tolerance", parameter_tolerance,
      "gn: converged when the step |dx| <= this * (|x| + this) []", Positive(1));
    v("linear_solver", linear_solver,
      "dense or sparse Cholesky of the Schur-reduced system (sparse: large windows), sparse_full (sparse Cholesky "
      "of the whole system, states eliminated before landmarks: whole sequences, batch's final solve) or iterative "
      "(preconditioned conjugate gradients on the reduced system)",
      {"dense", "sparse", "sparse_full", "iterative"});
    v("max_solver_time_s", max_solver_time_s,
      "wall-time bound of one solve [s]; 0 = none (default: results do not depend on machine load); a run that "
      "hits a bound is not reproducible",
      AtLeast(0));
    v("function_tolerance", function_tolerance, "relative cost change that counts as converged []", Positive(1));
    v("num_threads", num_threads, "Ceres threads [count]", Between(1, 256));
  }
};

/// Measurement models and their noise.
struct ModelOptions {
  double pixel_sigma = 0.5;        ///< stereo measurement noise, each of (u_L, u_R, v) [px]
  double huber_px = 1.5;           ///< Huber loss threshold in whitened units [sigma]; 0 = none
  double gravity = 9.81;           ///< gravity magnitude, world -z [m/s^2]
  double imu_noise_scale = 10.0;    ///< multiplies the IMU noise densities of sensor.yaml []
  double min_disparity_px = 1.0;   ///< new landmarks need at least this stereo disparity [px]
  double max_depth_m = 30.0;       ///< new landmarks beyond this depth are not added [m]
  double reintegrate_bias_threshold = 0.01;  ///< re-preintegrate when the gyro bias moved [rad/s]
  double max_whitened_residual = 50.0;  ///< observations of window landmarks predicted worse are rejected [sigma]
  double max_imu_gap_s = 0.1;          ///< longest IMU gap the estimate bridges; a longer one ends the run [s]
  bool fej = false;  ///< first-estimate Jacobians on every block in a prior (first_estimates.h)
  bool estimate_time_offset = true;       ///< the camera-IMU time offset is a state of the window
  double time_offset_prior_mean_ms = 0.0;   ///< prior mean of the offset (fixed when not estimated) [ms]
  double time_offset_prior_sigma_ms = 5.0;  ///< prior standard deviation of the offset [ms]
  bool estimate_extrinsics = false;         ///< a correction of the camera-IMU extrinsics is a state of the window
  double extrinsics_prior_sigma_deg = 1.0;  ///< prior standard deviation of its rotation, per axis [deg]
  double extrinsics_prior_sigma_m = 0.02;   ///< prior standard deviation of its translation, per axis [m]
  double time_offset_search_ms = 100.0;  ///< range of the coarse search at initialization, either side [ms]; 0: none
  bool extrinsics_rotation_search = true;  ///< the rig's rotation found from gyro against camera at initialization
  double extrinsics_probe_s = 0.0;       ///< longest probe of the extrinsics at the start [s]; 0: no probe
  double extrinsics_probe_min_deg = 0.5;  ///< smallest rotation correction the probe applies [deg]
  double extrinsics_probe_min_m = 0.01;   ///< smallest translation correction the probe applies [m]
  int extrinsics_probe_stride = 1;        ///< the probe's estimator takes every this-many-th frame [frames]

  template <class V>
  void Visit(V& v) {
    v("pixel_sigma", pixel_sigma, "stereo measurement noise of each of (u_L, u_R, v) [px]", Positive());
    v("huber_px", huber_px, "Huber loss threshold on whitened residuals [sigma]; 0 disables it", AtLeast(0));
    v("gravity", gravity, "gravity magnitude along world -z [m/s^2]", Positive());
    v("imu_noise_scale", imu_noise_scale, "factor on the IMU noise densities of sensor.yaml []", Positive());
    v("min_disparity_px", min_disparity_px, "smallest stereo disparity of a new landmark [px]", AtLeast(0));
    v("max_depth_m", max_depth_m, "largest depth of a new landmark [m]", Positive());
    v("reintegrate_bias_threshold", reintegrate_bias_threshold,
      "gyro-bias change that triggers re-preintegration [rad/s]", AtLeast(0));
    v("max_whitened_residual", max_whitened_residual,
      "an observation of a landmark in the window whose whitened reprojection error at the IMU-predicted state "
      "exceeds this is rejected before it reaches the cost [sigma]",
      Positive());
    v("max_imu_gap_s", max_imu_gap_s,
      "longest gap between IMU samples the estimate bridges; at a longer one the run stops (status imu_gap) and "
      "frames outside the IMU's span by more than this are reported (status frames_skipped) [s]",
      Positive());
    v("fej", fej,
      "first-estimate Jacobians: every factor's Jacobians on a block in a prior are taken at the value the block had "
      "when it entered its first prior (keeps yaw and position unobservable, as they are)");
    v("estimate_time_offset", estimate_time_offset,
      "estimate the camera-IMU time offset online, as a state of the window under a prior (docs/calibration.md); "
      "false: the prior mean is taken as exact");
    v("time_offset_prior_mean_ms", time_offset_prior_mean_ms,
      "camera-IMU time offset's prior mean: an image stamped t was taken at IMU time t - offset [ms]",
      Between(-1000, 1000));
    v("time_offset_prior_sigma_ms", time_offset_prior_sigma_ms,
      "camera-IMU time offset's prior standard deviation [ms]", Positive());
    v("estimate_extrinsics", estimate_extrinsics,
      "estimate a correction of the camera-IMU extrinsics (both cameras moved rigidly, the baseline kept) online, as "
      "a state of the window under a zero-mean prior (docs/calibration.md); false: sensor.yaml's T_BS is exact");
    v("extrinsics_prior_sigma_deg", extrinsics_prior_sigma_deg,
      "camera-IMU extrinsics correction's prior standard deviation of the rotation, per axis [deg]", Positive(90));
    v("extrinsics_prior_sigma_m", extrinsics_prior_sigma_m,
      "camera-IMU extrinsics correction's prior standard deviation of the translation, per axis [m]", Positive(10));
    v("time_offset_search_ms", time_offset_search_ms,
      "with estimate_time_offset: in the first seconds of rotation the gyro is matched to the camera for offsets "
      "this far either side of time_offset_prior_mean_ms; a match beyond the prior starts the run again with the "
      "prior's mean there, one at the range's end stops it (bad_input); 0: no search [ms]",
      Between(0, 1000));
    v("extrinsics_rotation_search", extrinsics_rotation_search,
      "in the first seconds of rotation the rig's rotation is fitted to the gyro's against the camera's (hand-eye); "
      "a rotation beyond 2 extrinsics_prior_sigma_deg (and 3 of its own sigmas) starts the run again with sensor.yaml's "
      "cameras turned by it (docs/calibration.md)");
    v("extrinsics_probe_s", extrinsics_probe_s,
      "without estimate_extrinsics: a second estimator (SWF, every extrinsics_probe_stride-th frame) runs beside the "
      "run's from the first frame with the extrinsics estimated, until their sigmas are below half of "
      "extrinsics_probe_min_deg / _m or this much frame time after its initialization has passed; a correction "
      "significant against its covariance (chi-square, 6 dof, 0.1 %) and at least extrinsics_probe_min_deg or "
      "extrinsics_probe_min_m starts the run again from the first frame with the rig corrected, else the probe is "
      "dropped and the run is the one without it (docs/calibration.md); 0: no probe; 30 is a good probe [s]",
      Between(0, 1000));
    v("extrinsics_probe_min_deg", extrinsics_probe_min_deg,
      "the extrinsics probe applies a correction only when its rotation is at least this or its translation at least "
      "extrinsics_probe_min_m [deg]",
      Positive(90));
    v("extrinsics_probe_min_m", extrinsics_probe_min_m,
      "the extrinsics probe applies a correction only when its translation is at least this or its rotation at least "
      "extrinsics_probe_min_deg [m]",
      Positive(10));
    v("extrinsics_probe_stride", extrinsics_probe_stride,
      "the extrinsics probe's estimator takes every this-many-th frame once initialized (the IMU preintegrated "
      "across the others, the tracks kept): its cost falls with it, the correction's accuracy too [frames]",
      Between(1, 20));
  }
};

/// How the first state is found.
struct InitOptions {
  std::string init = "auto";            ///< auto | static (IMU stillness) | dynamic (moving start) | groundtruth
  double static_window_s = 1.0;         ///< IMU span averaged for the initial biases (static: also gravity) [s]
  double static_max_gyro_std = 0.05;    ///< stillness: largest gyro standard deviation [rad/s]
  double static_max_accel_std = 0.8;    ///< stillness: largest accel standard deviation [m/s^2]
  double prior_position_sigma = 1e-3;   ///< first-pose prior on position [m]
  double prior_yaw_sigma = 1e-3;        ///< first-pose prior on yaw [rad]
  double prior_tilt_sigma = 0.02;       ///< first-pose prior on roll and pitch [rad]
  double prior_velocity_sigma = 0.05;   ///< first-state prior on velocity [m/s]
  double prior_gyro_bias_sigma = 0.01;  ///< first-state prior on the gyro bias [rad/s]
  double prior_accel_bias_sigma = 0.2;  ///< first-state prior on the accel bias [m/s^2]
  double static_max_camera_motion_px = 3.0;  ///< auto: a static start needs the image this still [px]
  double dynamic_window_s = 0.5;        ///< dynamic: span of the frames the first state is solved from [s]
  int dynamic_min_landmarks = 15;       ///< dynamic: landmarks with stereo depth shared by consecutive frames
  double dynamic_max_tilt_sigma = 0.05;     ///< dynamic: largest roll/pitch standard deviation to start [rad]
  double dynamic_max_velocity_sigma = 0.2;  ///< dynamic: largest velocity standard deviation to start [m/s]

  template <class V>
  void Visit(V& v) {
    v("init", init,
      "initialization: auto (static when the IMU and the camera are still, dynamic otherwise, whichever is ready "
      "first), static (IMU stillness), dynamic (from motion: stereo poses aligned with the preintegrated IMU, "
      "refined by a small bundle adjustment) or groundtruth",
      {"auto", "static", "dynamic", "groundtruth"});
    v("static_window_s", static_window_s,
      "IMU span averaged for the initial biases (static: also gravity; groundtruth: either side of the start) [s]",
      Positive());
    v("static_max_gyro_std", static_max_gyro_std, "stillness: largest gyro standard deviation [rad/s]", Positive());
    v("static_max_accel_std", static_max_accel_std, "stillness: largest accel standard deviation [m/s^2]", Positive());
    v("prior_position_sigma", prior_position_sigma, "first-pose prior on position [m]", Positive());
    v("prior_yaw_sigma", prior_yaw_sigma, "first-pose prior on yaw [rad]", Positive());
    v("prior_tilt_sigma", prior_tilt_sigma, "first-pose prior on roll and pitch [rad]", Positive());
    v("prior_velocity_sigma", prior_velocity_sigma, "first-state prior on velocity [m/s]", Positive());
    v("prior_gyro_bias_sigma", prior_gyro_bias_sigma, "first-state prior on the gyro bias [rad/s]", Positive());
    v("prior_accel_bias_sigma", prior_accel_bias_sigma, "first-state prior on the accel bias [m/s^2]", Positive());
    v("static_max_camera_motion_px", static_max_camera_motion_px,
      "auto: a static start also needs the image to move less than this over the static window (median "
      "displacement of the tracked landmarks) [px]",
      Positive());
    v("dynamic_window_s", dynamic_window_s, "dynamic: span of the frames the first state is solved from [s]",
      Positive());
    v("dynamic_min_landmarks", dynamic_min_landmarks,
      "dynamic: landmarks with stereo depth each pair of consecutive frames must share [count]", AtLeast(3));
    v("dynamic_max_tilt_sigma", dynamic_max_tilt_sigma,
      "dynamic: the run starts once roll and pitch are known to this standard deviation [rad]", Positive());
    v("dynamic_max_velocity_sigma", dynamic_max_velocity_sigma,
      "dynamic: the run starts once the velocity is known to this standard deviation [m/s]", Positive());
  }
};

/// Everything the estimator is configured with.
struct EstimatorOptions {
  PolicyOptions policy;
  MsckfOptions msckf;
  PersistentOptions persistent;
  LocalMapOptions local_map;
  BatchOptions batch;
  SmootherOptions smoother;
  SolverOptions solver;
  ModelOptions model;
  InitOptions init;
};

}  // namespace vio
