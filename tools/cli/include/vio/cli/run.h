#pragma once
// One estimator run over a dataset (`vio run`): read, rectify, estimate frame
// by frame, write the results, evaluate against ground truth when it exists.
//
// Output folder:
//   trajectory.txt  TUM text, body in world: t[s] x y z qx qy qz qw, one row per estimated frame; while
//                   the run goes, each frame's online estimate is appended (flushed) as it is made, and at
//                   the end the file is replaced whole (temporary file + rename) by the trajectory asked for
//   timing.csv      per frame: stage times [ms], solver iterations, window size
//   summary.json    counts (frame gaps, tracking loss), time per stage, real-time factor, peak memory,
//                   ATE/RPE (when ground truth exists)
//   config.yaml     the effective configuration
//   covariance.csv  with output_covariance: per frame, the newest state's marginal covariance (run_output.h)
//   nees.csv        with output_covariance and ground truth: per-frame NEES (nees.h), means in summary.json
//   observations.csv  with output_observations: the stereo observations given to the estimator
//                   (observations_csv.h; `vio matchcheck` checks them against a rendered dataset's scene)
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "vio/cli/run_config.h"
#include "vio/estimator/refinement.h"
#include "vio/estimator/tracking_monitor.h"
#include "vio/evaluation/nees.h"
#include "vio/evaluation/trajectory_eval.h"

namespace vio::tools {

struct RunRequest {
  std::string dataset_dir;   ///< EuRoC ASL folder (holding mav0/)
  std::string output_dir;    ///< created when missing
  RunConfig config;
  bool show_progress = true; ///< progress bar (only drawn on a terminal)
  bool output_covariance = false;  ///< write covariance.csv (one more linearization per frame)
  bool output_observations = false;  ///< write observations.csv (inside the timed loop: a little slower)
  /// trajectory.txt and the evaluation: "online" (each frame's pose as estimated at that frame) or
  /// "smoothed" (every frame refined after the online pass, from Estimator::LastEstimates: Estimator::Refine).
  /// batch writes its final solve either way.
  std::string trajectory = "online";
  /// Asked between frames and between solver iterations: a signal number (SIGINT, SIGTERM) ends
  /// the run there with status interrupted, writing what was estimated. Empty: never.
  std::function<int()> stop_signal;
};

/// What a run could not do or had to reject (summary.json "health").
struct RunHealth {
  int frames_waiting_init = 0;    ///< frames before initialization (static: IMU stillness over static_window_s)
  int frames_before_imu = 0;      ///< frames before the first IMU sample: not estimated
  int frames_after_imu = 0;       ///< frames after the last IMU sample: not estimated
  int frames_after_stop = 0;      ///< frames not processed because the run stopped early
  int rejected_observations = 0;  ///< observations beyond the whitened-residual gate
  int dropped_residuals = 0;      ///< residuals that did not evaluate at marginalization
  int failed_solves = 0;          ///< solves without a usable solution
  int rejected_steps = 0;         ///< Gauss-Newton steps undone: their end point did not evaluate
  int dropped_observations = 0;   ///< observations that failed at a rejected step's end point: dropped as outliers
};

/// A run that waits longer than this, or for more than this fraction of its frames, before its first
/// estimate has status late_init.
inline constexpr double kMaxInitWaitS = 2.0;
inline constexpr double kMaxInitWaitFraction = 0.05;

/// How the run started.
struct InitReport {
  std::string method;    ///< static, dynamic or groundtruth; empty when the run never started
  double wait_s = 0;     ///< from the first frame the IMU covers to the first estimate [s]
  int wait_frames = 0;   ///< frames before the first estimate (= health.frames_waiting_init)
  std::string last_reason;  ///< why it was still waiting at the last frame before it started
};

/// The online calibration's estimates at the end of the run (docs/calibration.md).
struct CalibrationReport {
  bool time_offset_estimated = false;
  double time_offset_ms = 0;  ///< an image stamped t was taken at IMU time t - offset [ms] (calibration's + estimate)
  double time_offset_calibration_ms = 0;  ///< the calibration's (Kalibr's -timeshift_cam_imu), applied first [ms]
  std::optional<double> time_offset_sigma_ms;  ///< marginal standard deviation, when estimated [ms]
  /// The coarse search at initialization (time_offset_search_ms), when it decided: its offset
  /// (calibration's + found) and standard deviation [ms], and whether the run started again with the
  /// prior's mean there (the offset lay beyond the prior).
  std::optional<double> time_offset_search_ms, time_offset_search_sigma_ms;
  bool time_offset_search_restarted = false;
  /// The extrinsics' correction (estimate_extrinsics): both cameras turned rigidly in the body by
  /// the rotation vector rotation_deg [deg] (body frame) and the left camera moved by translation_m
  /// [m] (body frame); the sigmas are the largest standard deviation over directions of each, when
  /// the covariance is available.
  bool extrinsics_estimated = false;
  Eigen::Vector3d extrinsics_rotation_deg = Eigen::Vector3d::Zero();
  Eigen::Vector3d extrinsics_translation_m = Eigen::Vector3d::Zero();
  std::optional<double> extrinsics_rotation_sigma_deg, extrinsics_translation_sigma_m;
  /// The rig rotation search at initialization (extrinsics_rotation_search), when it decided: the
  /// rig's turn it found (body frame) [deg], its largest sigma [deg], whether the motion told it, and
  /// whether the run started again with sensor.yaml's cameras turned by it.
  std::optional<Eigen::Vector3d> rig_rotation_search_deg;
  double rig_rotation_search_sigma_deg = 0;
  bool rig_rotation_search_excited = false;
  bool rig_rotation_search_restarted = false;
  /// The extrinsics probe (extrinsics_probe_s), when it decided (docs/calibration.md).
  struct ExtrinsicsProbe {
    double duration_s = 0;  ///< frame time from the first estimate to the decision [s]
    Eigen::Vector3d rotation_deg = Eigen::Vector3d::Zero();  ///< its rotation vector, body frame [deg]
    Eigen::Vector3d translation_m = Eigen::Vector3d::Zero();  ///< the left camera's move, body frame [m]
    std::optional<double> rotation_sigma_deg, translation_sigma_m;  ///< largest over directions
    std::optional<double> chi2;  ///< the correction's squared Mahalanobis norm (6 dof)
    bool applied = false;        ///< significant and large enough: the run started again with it
  };
  std::optional<ExtrinsicsProbe> extrinsics_probe;
};

struct RunResult {
  /// ok: every frame from initialization on estimated, every solve usable,
  /// within the sanity bounds; else the first of: imu_gap (stopped at an IMU
  /// gap longer than model.max_imu_gap_s), bad_input (stopped: the data shows the rig cannot
  /// be right, e.g. the IMU in wrong units or swapped cameras; rig_checks.h), diverged (|p| > 10 km, |v| > 100
  /// m/s or not finite), failed (an error mid-run), frames_skipped (frames
  /// outside the IMU span by more than max_imu_gap_s), not_initialized (no
  /// frame estimated), late_init (more than kMaxInitWaitS seconds or
  /// kMaxInitWaitFraction of the frames waited for initialization),
  /// solver_failure, drifted (ATE RMSE > 0.5 m + 5% of the path). Not ok =
  /// exit code 1 of `vio run`; what was estimated is written either way.
  /// interrupted: RunRequest::stop_signal ended the run (exit code 128 +
  /// signal); the frames estimated until then are written.
  std::string status = "ok";
  int stop_signal = 0;           ///< the signal that interrupted the run; 0 when none did
  /// What trajectory.txt holds: online, smoothed or final (an offline policy's final solve; when
  /// that solve was interrupted, the iterate it had reached).
  std::string trajectory = "online";
  std::vector<std::string> problems;  ///< one message per problem (file and line where there is one)
  int frames = 0;                ///< frames in the dataset
  int frames_estimated = 0;      ///< frames with a pose in trajectory.txt
  double dataset_duration_s = 0; ///< first to last frame [s]
  /// Wall time of the estimator loop [s]; both passes when the time offset search started the run again.
  double processing_s = 0;
  double ms_per_frame = 0;       ///< mean over estimated frames [ms]
  double real_time_factor = 0;   ///< dataset_duration_s / processing_s
  double peak_memory_mb = 0;     ///< peak resident set size of the process (getrusage) [MiB]
  RunHealth health;
  std::optional<double> groundtruth_tilt_deg;  ///< tilt of the ground truth's z from up (decides the alignment)
  int frame_gaps = 0;             ///< frame intervals longer than 1.5 median intervals (missing frames)
  double longest_frame_gap_s = 0; ///< longest frame interval [s]
  TrackingReport tracking;        ///< frames with too few observations (propagated on the IMU)
  InitReport init;
  CalibrationReport calibration;
  std::optional<TrajectoryEvaluation> evaluation;  ///< when ground truth exists
  std::optional<NeesResult> nees;  ///< with output_covariance, when ground truth exists (same alignment)
  RefinementReport refinement;     ///< trajectory=smoothed: the offline refinement's cost (in processing_s)
};

/// Runs and writes the output folder. Throws DatasetError / ConfigError /
/// std::runtime_error with a clear message on bad input.
RunResult RunDataset(const RunRequest& request);

}  // namespace vio::tools
