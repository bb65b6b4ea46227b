#include "vio/cli/run.h"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <optional>
#include <sstream>


#include <glog/logging.h>

#include "run_calibration.h"
#include "run_frames.h"
#include "run_probe.h"
#include "run_control.h"
#include "run_output.h"
#include "vio/estimator/estimator.h"
#include "vio/frontend/stereo_rectifier.h"
#include "vio/dataset/euroc_dataset.h"
#include "vio/cli/progress.h"
#include "vio/dataset/frame_source.h"
#include "vio/dataset/groundtruth_init.h"
#include "vio/dataset/kalibr_calibration.h"
#include "vio/dataset/observations_csv.h"
#include "vio/dataset/ros2_dataset.h"
#include "vio/dataset/rosbag_dataset.h"

namespace vio::tools {
namespace {

// --calibration: an ASL folder's sensor.yaml files or Kalibr's camchain (and imu.yaml).
void ApplyCalibration(const CalibrationOptions& options, EurocDataset* dataset) {
  if (!IsCalibrationFile(options.calibration)) {
    if (!options.calibration_imu.empty()) {
      throw ConfigError("--calibration_imu is for a Kalibr camchain given as --calibration (a file), not a folder");
    }
    ApplyCalibrationFrom(options.calibration, dataset);
    return;
  }
  const std::string imu = options.calibration_imu.empty() ? KalibrImuFileBeside(options.calibration)
                                                         : options.calibration_imu;
  const KalibrCalibration kalibr = ReadKalibr(options.calibration, imu);
  dataset->cameras[0] = kalibr.cameras[0];
  dataset->cameras[1] = kalibr.cameras[1];
  dataset->imu_calibration = kalibr.imu;
  dataset->camera_time_offset_ns = kalibr.camera_time_offset_ns;
  LOG(INFO) << "calibration from Kalibr's " << options.calibration << " and " << imu << " (camera time offset "
            << 1e-6 * static_cast<double>(kalibr.camera_time_offset_ns) << " ms)";
}

EurocDataset ReadRunDataset(const RunRequest& request) {
  const bool ros2 = IsRos2BagPath(request.dataset_dir);
  if (ros2 || IsBagPath(request.dataset_dir)) {
    if (request.config.calibration.calibration.empty()) {
      throw std::runtime_error(request.dataset_dir + ": a ROS recording carries no calibration: give "
                               "--calibration=DIR (a folder with mav0/{cam0,cam1,imu0}/sensor.yaml)");
    }
    EurocDataset dataset = ros2 ? ReadRos2Bag(request.dataset_dir, request.config.bag)
                                : ReadBag(request.dataset_dir, request.config.bag);
    ApplyCalibration(request.config.calibration, &dataset);
    return dataset;
  }
  EurocReadOptions read;
  read.check_images = request.config.frontend.frontend != "features";
  read.stream_features = true;  // read frame by frame in the run loop, never held whole
  EurocDataset dataset = ReadEuroc(request.dataset_dir, read);
  if (!request.config.calibration.calibration.empty()) ApplyCalibration(request.config.calibration, &dataset);
  return dataset;
}

double PeakMemoryMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

// The offline policy's final estimates replace the per-frame ones. A final
// solve stopped by a signal keeps the iterate it reached (status interrupted).
void FinishEstimates(const RunRequest& request, Estimator& estimator, RunOutput& output,
                     const SolveProgressLog& solve_log, RunResult* result) {
  try {
    const std::vector<FrameEstimate> final_estimates = estimator.Finish();
    output.ReplaceEstimates(final_estimates);
    if (!final_estimates.empty()) result->trajectory = "final";
    if (estimator.window().health().stopped_solves == 0) return;
    result->status = "interrupted";
    result->stop_signal = StopSignalOf(request);
    std::ostringstream message;
    message << "interrupted by " << SignalName(result->stop_signal)
            << " in the final solve: trajectory.txt holds the iterate it had reached";
    if (const std::optional<SolveProgress>& last = solve_log.last()) {
      message << " (iteration " << last->iteration << " of " << last->max_iterations << ", cost "
              << last->initial_cost << " -> " << last->cost << ")";
    }
    message << ", not its converged solution";
    LOG(WARNING) << message.str();
    result->problems.push_back(message.str());
  } catch (const std::exception& e) {
    const std::string message = std::string("final solve: ") + e.what() + " (the per-frame estimates are kept)";
    LOG(ERROR) << message;
    result->status = "failed";
    result->problems.push_back(message);
  }
}

// --trajectory=smoothed: the offline refinement of every frame replaces the
// last estimates; stopped by a signal, the iterate it reached (status interrupted).
void RefineEstimates(const RunRequest& request, const Estimator& estimator, RunOutput& output, RunResult* result) {
  const std::vector<FrameEstimate> refined = estimator.Refine(&result->refinement);
  if (result->refinement.stopped) {
    result->status = "interrupted";
    result->stop_signal = StopSignalOf(request);
    const std::string message = "interrupted by " + SignalName(result->stop_signal) + " in the refinement: " +
                                (refined.empty() ? "the frames' last estimates are written"
                                                 : "trajectory.txt holds the iterate it had reached");
    LOG(WARNING) << message;
    result->problems.push_back(message);
  }
  if (!refined.empty()) {
    output.ReplaceEstimates(refined);
    if (const std::optional<double> offset = result->refinement.time_offset_s) {  // what the trajectory was solved with
      result->calibration.time_offset_ms = result->calibration.time_offset_calibration_ms + 1e3 * *offset;
      result->calibration.time_offset_sigma_ms.reset();
    }
    return;
  }
  if (!result->refinement.ran || result->refinement.stopped) return;
  result->problems.push_back("refinement: no usable solution (the frames' last estimates are kept)");
  result->status = "solver_failure";
}

// A run that waited more than kMaxInitWaitS or kMaxInitWaitFraction of its
// frames before its first estimate lost that part of the trajectory: not ok.
void CheckLateInit(RunResult* result) {
  result->init.wait_frames = result->health.frames_waiting_init;
  if (result->frames_estimated == 0 || result->frames == 0) return;
  const double fraction = static_cast<double>(result->init.wait_frames) / result->frames;
  if (result->init.wait_s <= kMaxInitWaitS && fraction <= kMaxInitWaitFraction) return;
  std::ostringstream why;
  why << std::fixed << std::setprecision(2) << "late initialization (" << result->init.method << "): waited "
      << result->init.wait_s << " s and " << result->init.wait_frames << " frames (" << 100 * fraction
      << "% of the run; limits " << kMaxInitWaitS << " s, " << 100 * kMaxInitWaitFraction
      << "%) before the first estimate; those frames are not estimated; last reason: " << result->init.last_reason;
  LOG(WARNING) << why.str();
  result->problems.push_back(why.str());
  if (result->status == "ok") result->status = "late_init";
}

// Counts from the estimator, and the statuses that need the whole run.
void FinishStatus(const Estimator& estimator, RunResult* result) {
  result->health.rejected_observations = estimator.rejected_observations();
  result->health.dropped_residuals = estimator.window().health().dropped_residuals;
  result->health.failed_solves = estimator.window().health().failed_solves;
  result->health.rejected_steps = estimator.window().health().rejected_steps;
  result->health.dropped_observations = estimator.window().health().dropped_observations;
  if (result->frames_estimated == 0 && result->status == "ok") result->status = "not_initialized";
  CheckLateInit(result);
  if (result->health.failed_solves > 0) {
    result->problems.push_back(std::to_string(result->health.failed_solves) +
                               " solves ended without a usable solution");
    if (result->status == "ok") result->status = "solver_failure";
  }
  if (result->health.dropped_residuals > 0) {
    result->problems.push_back(std::to_string(result->health.dropped_residuals) +
                               " residuals did not evaluate at marginalization and were dropped");
  }
}

// ATE RMSE beyond 0.5 m + 5% of the ground-truth path is no estimate: the
// documented sanity bound of status "drifted".
void CheckDrift(const TrajectoryEvaluation& evaluation, double path_length_m, RunResult* result) {
  const double bound_m = 0.5 + 0.05 * path_length_m;
  if (evaluation.ate.rmse_m <= bound_m) return;
  std::ostringstream why;
  why << "ATE RMSE " << evaluation.ate.rmse_m << " m exceeds the sanity bound " << bound_m
      << " m (0.5 m + 5% of the " << path_length_m << " m ground-truth path)";
  LOG(ERROR) << why.str();
  result->problems.push_back(why.str());
  if (result->status == "ok") result->status = "drifted";
}

double PathLength(const std::vector<GroundTruthState>& gt, Timestamp from_ns, Timestamp to_ns) {
  double length = 0;
  for (size_t i = 1; i < gt.size(); ++i) {
    if (gt[i - 1].t_ns >= from_ns && gt[i].t_ns <= to_ns) length += (gt[i].p_w_b - gt[i - 1].p_w_b).norm();
  }
  return length;
}

// pos+yaw alignment assumes both worlds have z up; a ground truth whose world
// is tilted (a calibration target) is aligned in SE3.
Alignment SummaryAlignment(const EurocDataset& dataset, double gravity, RunResult* result) {
  const std::optional<double> tilt = GroundTruthTiltDeg(dataset.groundtruth, dataset.imu, gravity);
  result->groundtruth_tilt_deg = tilt;
  return tilt && *tilt > kMaxPosYawTiltDeg ? Alignment::kSe3 : Alignment::kPosYaw;
}

void Evaluate(const EurocDataset& dataset, const RunRequest& request, const RunOutput& output, RunResult* result) {
  if (dataset.groundtruth.empty() || result->frames_estimated < 3) return;
  EvaluationOptions options;
  options.alignment = SummaryAlignment(dataset, request.config.estimator.model.gravity, result);
  result->evaluation = EvaluateTrajectory(output.trajectory(), dataset.groundtruth, options);
  if (request.output_covariance) {
    result->nees = EvaluateNees(output.trajectory(), dataset.groundtruth, output.PoseCovariances(), options);
  }
  const std::vector<GroundTruthState>& estimated = output.trajectory();
  CheckDrift(*result->evaluation,
             PathLength(dataset.groundtruth, estimated.front().t_ns, estimated.back().t_ns), result);
}

// Valid settings that usually give a worse estimate than the user wants: a warning each.
void WarnAboutQuestionableSettings(const RunConfig& config) {
  const int kept = config.estimator.persistent.persistent_landmarks;
  if (kept > 0 && !config.estimator.model.fej) {
    LOG(WARNING) << "--persistent_landmarks=" << kept
                 << " without --fej=true: the kept landmarks' relinearized observations disagree with the prior "
                    "they are in, which usually makes the estimate worse (docs/design.md: Long-lived landmarks)";
  }
}

// The request's own settings (the configuration's are ValidateRunConfig's).
void ValidateRequest(const RunRequest& request) {
  if (request.trajectory != "online" && request.trajectory != "smoothed") {
    throw ConfigError("--trajectory='" + request.trajectory + "': expected online or smoothed");
  }
  if (request.trajectory == "smoothed" && request.output_covariance) {
    throw ConfigError("--trajectory=smoothed with --output_covariance: the covariances are of each frame's online "
                      "estimate (the newest state), not of the smoothed one; use one or the other");
  }
}

// How a pass ended: at the data's end (or a stop), at a search's request to start again, or at the
// extrinsics probe's decision to correct the rig (nothing is written at either).
enum class PassEnd { kFinished, kSearch, kProbe };

// One pass over the dataset. `searches`: the searches' results of an earlier pass that ended at them
// (this one runs with the rig they found), else empty and filled when this pass's searches ask to
// start again. `probe` (null: none): undecided, it runs in lockstep with this pass's estimator;
// decided, the rig it found is this pass's when it applied it. `earlier_pass_s`: the earlier passes' processing time, counted in this one's.
RunResult RunPass(const RunRequest& requested, const EurocDataset& dataset, InitSearches* searches,
                  ExtrinsicsProbe* probe, double earlier_pass_s, PassEnd* end) {
  RunRequest request = requested;
  request.config.frontend.frontend = ResolveFrontend(requested.config.frontend.frontend, dataset);
  const frontend::StereoRectifier rectifier(dataset.cameras[0], dataset.cameras[1]);
  // An image stamped t was taken at IMU time t - camera_time_offset_ns: the frames move onto the IMU's clock.
  const std::unique_ptr<FrameSource> source = ShiftFrameTimes(
      MakeFrameSource(request.config.frontend, dataset, rectifier), -dataset.camera_time_offset_ns);
  if (request.config.estimator.init.init == "groundtruth" && dataset.groundtruth.empty()) {
    throw std::runtime_error(request.dataset_dir + ": --init=groundtruth but the dataset has no ground truth");
  }
  const bool probing = probe != nullptr && !probe->decided();
  const RectifiedStereo rig =
      probe != nullptr && probe->applied() ? probe->rig() : TurnedRig(rectifier.rectified(), *searches);
  Estimator estimator(request.config.estimator, dataset.imu_calibration, rig);
  if (probing) probe->Start(request.config.estimator, dataset.imu_calibration, rig);
  const bool refine = request.trajectory == "smoothed" && request.config.estimator.policy.policy != "batch";
  if (refine) estimator.KeepMeasurements();
  RunOutput output(request.output_dir);
  RunResult result;
  result.trajectory = request.trajectory;
  const auto num_frames = static_cast<std::int64_t>(source->size());
  ProgressBar progress = request.show_progress ? ProgressBar(num_frames, "frames")
                                               : ProgressBar(num_frames, "frames", nullptr, false);
  SolveProgressLog solve_log(&progress);
  estimator.SetSolveControl(MakeSolveControl(request, &solve_log));
  result.frames = static_cast<int>(source->size());
  if (source->size() > 0) {
    result.dataset_duration_s = NanosToSeconds(source->time(source->size() - 1) - source->time(0));
  }
  CountFrameGaps(*source, &result);
  const auto start = std::chrono::steady_clock::now();
  std::optional<ObservationsCsvWriter> observations;
  if (request.output_observations) observations.emplace(request.output_dir + "/observations.csv");
  *end = PassEnd::kFinished;
  if (EstimateFrames(request, dataset, *source, estimator, output, observations ? &*observations : nullptr,
                     probing ? probe : nullptr, progress, &result)) {
    *end = estimator.restart_requested() ? PassEnd::kSearch : PassEnd::kProbe;
  } else if (probing && probe->running() && result.status != "interrupted") {  // the data ended first
    probe->Finish();
    if (probe->applied()) *end = PassEnd::kProbe;
  }
  if (*end != PassEnd::kFinished) {
    progress.Stop();
    if (*end == PassEnd::kSearch) *searches = InitSearches{estimator.time_offset_search(), estimator.rig_rotation_search()};
    result.processing_s =
        earlier_pass_s + std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
  }
  if (observations) observations->Close();
  result.tracking = estimator.tracking();
  // Every frame's state as last estimated, whether the run finished or stopped.
  if (request.trajectory == "smoothed") output.ReplaceEstimates(estimator.LastEstimates());
  if (result.status == "ok") {
    solve_log.SetPhase("final solve");
    FinishEstimates(request, estimator, output, solve_log, &result);
  }
  // After the final solve: batch's offset is the whole sequence's, not its online estimate's.
  const InitSearches found = searches->restart()
                                 ? *searches
                                 : InitSearches{estimator.time_offset_search(), estimator.rig_rotation_search()};
  RecordCalibration(dataset, estimator, found, rectifier.rectified().T_b_cl, &result.calibration);
  if (probe != nullptr) result.calibration.extrinsics_probe = probe->report();
  if (estimator.window().estimates_extrinsics() || searches->restart() || (probe != nullptr && probe->applied())) {
    WriteCalibration(dataset, estimator.window(), rectifier.rectified().T_b_cl, request.output_dir + "/calibration");
  }
  if (refine && result.status == "ok") {
    solve_log.SetPhase("refinement");
    RefineEstimates(request, estimator, output, &result);
  }
  if (result.status == "interrupted") {
    progress.Stop();
  } else {
    progress.Finish();
  }
  ReportFramesOutsideImu(dataset, *source, request.config.estimator.model.max_imu_gap_s, &result);
  result.processing_s =
      earlier_pass_s + std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  FinishStatus(estimator, &result);
  result.ms_per_frame = result.frames_estimated ? 1e3 * result.processing_s / result.frames_estimated : 0.0;
  result.real_time_factor = result.processing_s > 0 ? result.dataset_duration_s / result.processing_s : 0.0;
  Evaluate(dataset, request, output, &result);
  output.WriteTrajectory();
  output.WriteTiming(result.refinement);
  result.peak_memory_mb = PeakMemoryMb();
  output.WriteSummary(result, source->ReportJson(), request, result.peak_memory_mb, estimator.waiting_reason());
  output.WriteConfig(RunConfigToYaml(request.config));
  if (request.output_covariance) output.WriteCovariance();
  if (result.nees) output.WriteNees(*result.nees);
  return result;
}

}  // namespace

// A search at initialization found the camera-IMU time offset or the rig's rotation beyond its prior,
// or the extrinsics probe found the rig off: the run starts again from the first frame (docs/calibration.md).
// At most three passes: the searches' results and the probe's decision each end one once.
RunResult RunDataset(const RunRequest& requested) {
  ValidateRunConfig(requested.config);
  ValidateRequest(requested);
  WarnAboutQuestionableSettings(requested.config);
  const EurocDataset dataset = ReadRunDataset(requested);
  std::optional<ExtrinsicsProbe> probe;
  if (ProbesExtrinsics(requested.config)) probe.emplace(requested.config.estimator.model);
  InitSearches searches;
  RunRequest request = requested;  // with the searches' results once they asked to start again
  double elapsed_s = 0;
  for (;;) {
    PassEnd end = PassEnd::kFinished;
    RunResult result = RunPass(request, dataset, &searches, probe ? &*probe : nullptr, elapsed_s, &end);
    if (end == PassEnd::kFinished) return result;
    elapsed_s = result.processing_s;
    if (end == PassEnd::kSearch) request = AfterSearches(request, searches, !probe.has_value());
    // A probe that gave up before the searches' restart probes the next pass again.
    if (end == PassEnd::kSearch && probe) probe.emplace(request.config.estimator.model);
    // The probe's rig holds any turn the rig rotation search found before it.
    if (end == PassEnd::kProbe && probe->applied()) request.config.estimator.model.extrinsics_rotation_search = false;
  }
}

}  // namespace vio::tools
