#include "vio/cli/run.h"

#include <sys/resource.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include <glog/logging.h>

#include "run_output.h"
#include "vio/estimator/estimator.h"
#include "vio/frontend/stereo_rectifier.h"
#include "vio/dataset/euroc_dataset.h"
#include "vio/cli/progress.h"
#include "vio/dataset/frame_source.h"
#include "vio/dataset/groundtruth_init.h"

namespace vio::tools {
namespace {

// The dataset's calibration, or the one of the folder the config names.
void ApplyCalibrationSource(const CalibrationOptions& options, EurocDataset* dataset) {
  if (options.calibration.empty()) return;
  EurocReadOptions calibration_only;
  calibration_only.read_imu = calibration_only.read_groundtruth = calibration_only.read_features = false;
  calibration_only.check_images = false;
  const EurocDataset calibration = ReadEuroc(options.calibration, calibration_only);
  dataset->cameras[0] = calibration.cameras[0];
  dataset->cameras[1] = calibration.cameras[1];
  dataset->imu_calibration = calibration.imu_calibration;
}

EurocDataset ReadRunDataset(const RunRequest& request) {
  EurocReadOptions read;
  read.check_images = request.config.frontend.frontend != "features";
  EurocDataset dataset = ReadEuroc(request.dataset_dir, read);
  ApplyCalibrationSource(request.config.calibration, &dataset);
  return dataset;
}

// Ground truth at t_ns (linear in position, velocity and biases; slerp in
// rotation), or nothing outside its span.
bool Diverged(const FrameEstimate& e) {
  return !e.p_w_b.allFinite() || !e.q_w_b.coeffs().allFinite() || e.p_w_b.norm() > 1e4 || e.v_w_b.norm() > 100;
}

double PeakMemoryMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

// Gives the estimator the IMU up to and including the first sample at or
// after t_ns; false when the IMU ends before t_ns.
bool FeedImuUpTo(const std::vector<ImuSample>& imu, Timestamp t_ns, size_t* next, Estimator* estimator) {
  while (*next < imu.size() && (*next == 0 || imu[*next - 1].t_ns < t_ns)) estimator->AddImu(imu[(*next)++]);
  return *next > 0 && imu[*next - 1].t_ns >= t_ns;
}

// The frame loop: IMU, (ground-truth start), front end, estimator, output.
void EstimateFrames(const RunRequest& request, const EurocDataset& dataset, FrameSource& source,
                    Estimator& estimator, RunOutput& output, RunResult* result) {
  const auto num_frames = static_cast<std::int64_t>(source.size());
  ProgressBar progress = request.show_progress ? ProgressBar(num_frames, "frames")
                                               : ProgressBar(num_frames, "frames", nullptr, false);
  const bool init_from_gt = request.config.estimator.init.init == "groundtruth";
  size_t next_imu = 0;
  for (size_t k = 0; k < source.size(); ++k) {
    if (!FeedImuUpTo(dataset.imu, source.time(k), &next_imu, &estimator)) break;
    if (init_from_gt && result->frames_estimated == 0) {
      const InitOptions& init = request.config.estimator.init;
      const std::optional<InitialState> gt = GroundTruthInitialState(
          dataset.groundtruth, dataset.imu, source.time(k), request.config.estimator.model.gravity, init.static_window_s);
      if (!gt) continue;  // frame before the ground-truth span: no state to start from
      estimator.SetInitialState(*gt);
    }
    const FrameEstimate estimate = estimator.ProcessFrame(source.Frame(k, estimator));
    progress.Update(static_cast<std::int64_t>(k + 1));
    if (!estimate.initialized) continue;
    if (Diverged(estimate)) {
      result->status = "diverged";
      LOG(ERROR) << "estimate diverged at t=" << NanosToSeconds(estimate.t_ns) << " s (frame " << k << ")";
      break;
    }
    output.AddFrame(estimate);
    ++result->frames_estimated;
  }
  progress.Finish();
}

}  // namespace

RunResult RunDataset(const RunRequest& request) {
  const EurocDataset dataset = ReadRunDataset(request);
  const frontend::StereoRectifier rectifier(dataset.cameras[0], dataset.cameras[1]);
  const std::unique_ptr<FrameSource> source = MakeFrameSource(request.config.frontend, dataset, rectifier);
  if (request.config.estimator.init.init == "groundtruth" && dataset.groundtruth.empty()) {
    throw std::runtime_error(request.dataset_dir + ": --init=groundtruth but the dataset has no ground truth");
  }
  Estimator estimator(request.config.estimator, dataset.imu_calibration, rectifier.rectified());
  RunOutput output(request.output_dir);
  RunResult result;
  result.frames = static_cast<int>(source->size());
  if (source->size() > 0) {
    result.dataset_duration_s = NanosToSeconds(source->time(source->size() - 1) - source->time(0));
  }
  const auto start = std::chrono::steady_clock::now();
  EstimateFrames(request, dataset, *source, estimator, output, &result);
  if (result.status == "ok") output.ReplaceEstimates(estimator.Finish());
  result.processing_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (result.frames_estimated == 0 && result.status == "ok") result.status = "not_initialized";
  result.ms_per_frame = result.frames_estimated ? 1e3 * result.processing_s / result.frames_estimated : 0.0;
  result.real_time_factor = result.processing_s > 0 ? result.dataset_duration_s / result.processing_s : 0.0;
  if (!dataset.groundtruth.empty() && result.frames_estimated >= 3) {
    result.evaluation = EvaluateTrajectory(output.trajectory(), dataset.groundtruth);
  }
  output.WriteTrajectory();
  output.WriteTiming();
  output.WriteSummary(result, source->ReportJson(), request, PeakMemoryMb(), estimator.waiting_reason());
  output.WriteConfig(RunConfigToYaml(request.config));
  return result;
}

}  // namespace vio::tools
