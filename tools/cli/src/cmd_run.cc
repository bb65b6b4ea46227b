// `vio run`: the estimator over one dataset.
#include <iostream>

#include <gflags/gflags.h>

#include "commands.h"
#include "vio/cli/run.h"
#include "vio/cli/stop_signal.h"

DEFINE_string(dataset, "",
              "EuRoC ASL dataset folder (holding mav0/) with features0/data.csv or images, a ROS 1 bag (FILE.bag) "
              "or a ROS 2 recording (FILE.mcap, FILE.db3 or a bag folder with metadata.yaml; with --calibration)");
DEFINE_bool(output_covariance, false,
            "write covariance.csv: per frame, the newest state's marginal covariance (pose 6x6 upper triangle, "
            "velocity and bias variances) from the window's information");
DEFINE_bool(output_observations, false,
            "write observations.csv: every stereo observation given to the estimator (timestamp, landmark id, "
            "rectified u_L, u_R, v), for `vio matchcheck`");
DEFINE_string(trajectory, "online",
              "which pose of each frame trajectory.txt and the evaluation hold: online (as estimated at that frame, "
              "what a real-time user gets) or smoothed (after the online pass, every frame refined by one global "
              "solve of all states, landmarks and IMU factors started from each frame's and landmark's last estimate: "
              "as it left the window, or the local map's; its cost in summary.json's refinement and timing.csv's last line); "
              "batch writes its final solve either way {online|smoothed}");
DEFINE_string(config, "", "run configuration YAML (e.g. config/euroc_stereo.yaml); flags override it");

namespace vio::tools {

int RunMain(const std::vector<std::string>& args) {
  if (!args.empty()) {
    std::cerr << "vio run: unexpected argument '" << args.front() << "' (flags are --name=value; see `vio run --help`)\n";
    return 2;
  }
  if (FLAGS_dataset.empty() || FLAGS_output_dir.empty()) {
    std::cerr << "vio run: " << (FLAGS_dataset.empty() ? "--dataset" : "--output_dir")
              << " is required (see `vio run --help`)\n";
    return 2;
  }
  RunRequest request;
  request.dataset_dir = FLAGS_dataset;
  request.output_dir = FLAGS_output_dir;
  request.config = LoadRunConfig(FLAGS_config);
  request.output_covariance = FLAGS_output_covariance;
  request.output_observations = FLAGS_output_observations;
  request.trajectory = FLAGS_trajectory;
  InstallStopSignalHandlers();
  request.stop_signal = &StopSignal;
  const RunResult result = RunDataset(request);
  std::cout << "status " << result.status << ": " << result.frames_estimated << "/" << result.frames
            << " frames, " << result.ms_per_frame << " ms per frame, " << result.real_time_factor
            << "x real time, peak memory " << result.peak_memory_mb << " MB\n";
  if (result.evaluation) std::cout << ToText(*result.evaluation);
  std::cout << "results in " << request.output_dir << "\n";
  for (const std::string& problem : result.problems) std::cerr << "vio run: " << problem << "\n";
  if (result.stop_signal != 0) return InterruptedExitCode(result.stop_signal);
  return result.status == "ok" ? 0 : 1;
}

}  // namespace vio::tools
