#pragma once
// One estimator run over a dataset (`vio run`): read, rectify, estimate frame
// by frame, write the results, evaluate against ground truth when it exists.
//
// Output folder:
//   trajectory.txt  TUM text, body in world: t[s] x y z qx qy qz qw, one row per estimated frame
//   timing.csv      per frame: stage times [ms], solver iterations, window size
//   summary.json    counts (frame gaps, tracking loss), time per stage, real-time factor, peak memory,
//                   ATE/RPE (when ground truth exists)
//   config.yaml     the effective configuration
#include <optional>
#include <string>

#include "vio/cli/run_config.h"
#include "vio/estimator/tracking_monitor.h"
#include "vio/evaluation/trajectory_eval.h"

namespace vio::tools {

struct RunRequest {
  std::string dataset_dir;   ///< EuRoC ASL folder (holding mav0/)
  std::string output_dir;    ///< created when missing
  RunConfig config;
  bool show_progress = true; ///< progress bar (only drawn on a terminal)
};

struct RunResult {
  std::string status = "ok";     ///< ok | diverged | not_initialized
  int frames = 0;                ///< frames in the dataset
  int frames_estimated = 0;      ///< frames with a pose in trajectory.txt
  double dataset_duration_s = 0; ///< first to last frame [s]
  double processing_s = 0;       ///< wall time of the estimator loop [s]
  double ms_per_frame = 0;       ///< mean over estimated frames [ms]
  double real_time_factor = 0;   ///< dataset_duration_s / processing_s
  int frame_gaps = 0;             ///< frame intervals longer than 1.5 median intervals (missing frames)
  double longest_frame_gap_s = 0; ///< longest frame interval [s]
  TrackingReport tracking;        ///< frames with too few observations (propagated on the IMU)
  std::optional<TrajectoryEvaluation> evaluation;  ///< when ground truth exists
};

/// Runs and writes the output folder. Throws DatasetError / ConfigError /
/// std::runtime_error with a clear message on bad input.
RunResult RunDataset(const RunRequest& request);

}  // namespace vio::tools
