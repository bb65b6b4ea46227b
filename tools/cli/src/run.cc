#include "vio/cli/run.h"

#include <sys/resource.h>

#include <algorithm>
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
#include "vio/dataset/rosbag_dataset.h"

namespace vio::tools {
namespace {

EurocDataset ReadRunDataset(const RunRequest& request) {
  if (IsBagPath(request.dataset_dir)) {
    if (request.config.calibration.calibration.empty()) {
      throw std::runtime_error(request.dataset_dir + ": a ROS bag carries no calibration: give --calibration=DIR "
                               "(a folder with mav0/{cam0,cam1,imu0}/sensor.yaml)");
    }
    EurocDataset dataset = ReadBag(request.dataset_dir, request.config.bag);
    ApplyCalibrationFrom(request.config.calibration.calibration, &dataset);
    return dataset;
  }
  EurocReadOptions read;
  read.check_images = request.config.frontend.frontend != "features";
  EurocDataset dataset = ReadEuroc(request.dataset_dir, read);
  if (!request.config.calibration.calibration.empty()) {
    ApplyCalibrationFrom(request.config.calibration.calibration, &dataset);
  }
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

// Frame intervals longer than 1.5 median intervals: missing frames.
void CountFrameGaps(const FrameSource& source, RunResult* result) {
  std::vector<Timestamp> intervals;
  for (size_t k = 1; k < source.size(); ++k) intervals.push_back(source.time(k) - source.time(k - 1));
  if (intervals.empty()) return;
  std::vector<Timestamp> sorted = intervals;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double gap_ns = 1.5 * static_cast<double>(sorted[sorted.size() / 2]);
  for (Timestamp dt : intervals) {
    result->frame_gaps += static_cast<double>(dt) > gap_ns;
    result->longest_frame_gap_s = std::max(result->longest_frame_gap_s, NanosToSeconds(dt));
  }
  if (result->frame_gaps > 0) {
    LOG(INFO) << result->frame_gaps << " frame gaps (intervals over 1.5 median intervals), longest "
              << result->longest_frame_gap_s << " s";
  }
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

RunResult RunDataset(const RunRequest& requested) {
  const EurocDataset dataset = ReadRunDataset(requested);
  RunRequest request = requested;
  request.config.frontend.frontend = ResolveFrontend(requested.config.frontend.frontend, dataset);
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
  CountFrameGaps(*source, &result);
  const auto start = std::chrono::steady_clock::now();
  EstimateFrames(request, dataset, *source, estimator, output, &result);
  result.tracking = estimator.tracking();
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
