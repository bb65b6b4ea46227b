#include "run_frames.h"

#include <algorithm>
#include <iomanip>
#include <optional>
#include <sstream>

#include <glog/logging.h>

#include "run_control.h"
#include "vio/dataset/groundtruth_init.h"

namespace vio::tools {
namespace {

// A state no flight reaches: the estimate has diverged.
bool Diverged(const FrameEstimate& e) {
  return !e.p_w_b.allFinite() || !e.q_w_b.coeffs().allFinite() || e.p_w_b.norm() > 1e4 || e.v_w_b.norm() > 100;
}

// Where the frame loop is in the IMU, and the first gap it found.
struct ImuCursor {
  const EurocDataset& dataset;
  double max_gap_s;
  size_t next = 0;

  // "imu0/data.csv:LINE" of sample i, and "line N" of the one before (or
  // their times when the IMU was not read from a file).
  bool HasLines() const { return dataset.imu_lines.size() == dataset.imu.size() && !dataset.imu_file.empty(); }
  std::string Where(size_t i) const {
    if (!HasLines()) return "IMU sample at t=" + std::to_string(NanosToSeconds(dataset.imu[i].t_ns)) + " s";
    return dataset.imu_file + ":" + std::to_string(dataset.imu_lines[i]);
  }
  std::string Previous(size_t i) const {
    if (!HasLines()) return "the sample at t=" + std::to_string(NanosToSeconds(dataset.imu[i].t_ns)) + " s";
    return "line " + std::to_string(dataset.imu_lines[i]);
  }

  // Gives the estimator the IMU up to and including the first sample at or
  // after t_ns. A gap longer than max_gap_s after initialization stops there
  // and returns its description.
  std::optional<std::string> FeedUpTo(Timestamp t_ns, bool initialized, Estimator* estimator) {
    const std::vector<ImuSample>& imu = dataset.imu;
    while (next < imu.size() && (next == 0 || imu[next - 1].t_ns < t_ns)) {
      const double gap_s = next == 0 ? 0.0 : NanosToSeconds(imu[next].t_ns - imu[next - 1].t_ns);
      if (initialized && gap_s > max_gap_s) {
        std::ostringstream why;
        why << Where(next) << ": IMU gap of " << gap_s << " s after " << Previous(next - 1)
            << " (longer than model.max_imu_gap_s = " << max_gap_s << " s): the estimate cannot bridge it; "
            << "the run stops at t=" << std::fixed << std::setprecision(3) << NanosToSeconds(imu[next - 1].t_ns)
            << " s";
        return why.str();
      }
      estimator->AddImu(imu[next++]);
    }
    return std::nullopt;
  }
};

// Ends the loop at frame k with `status`: the frames left are counted.
void StopAt(size_t k, size_t num_frames, const std::string& status, const std::string& message, RunResult* result) {
  LOG(ERROR) << message;
  result->status = status;
  result->problems.push_back(message);
  result->health.frames_after_stop = static_cast<int>(num_frames - k);
}

// Ends the loop at frame k (not estimated) because `signal` asked the run to stop.
void Interrupt(size_t k, size_t num_frames, int signal, RunResult* result) {
  result->status = "interrupted";
  result->stop_signal = signal;
  result->health.frames_after_stop = static_cast<int>(num_frames - k);
  const std::string message = "interrupted by " + SignalName(signal) + " at frame " + std::to_string(k) + " of " +
                              std::to_string(num_frames) + ": the " + std::to_string(result->frames_estimated) +
                              " frames estimated until then are written";
  LOG(WARNING) << message;
  result->problems.push_back(message);
}

// What the data shows cannot be right (rig_checks.h, swapped cameras): the run stops with it.
std::string InputProblem(const FrameSource& source, const Estimator& estimator) {
  const std::string from_frames = source.InputProblem();
  if (!from_frames.empty()) return "bad input: " + from_frames;
  return estimator.input_problem().empty() ? "" : "bad input: " + estimator.input_problem();
}

// At the first estimate: the initializer's estimates of earlier frames
// (they stop counting as waiting), and how long the run waited.
void AddEarlierEstimates(Estimator& estimator, Timestamp first_covered_ns, Timestamp t_ns, RunOutput& output,
                         RunResult* result) {
  Timestamp first_ns = t_ns;
  for (const FrameEstimate& earlier : estimator.TakeEarlierEstimates()) {
    if (earlier.t_ns < first_covered_ns || earlier.t_ns >= t_ns) continue;
    output.AddFrame(earlier);
    ++result->frames_estimated;
    --result->health.frames_waiting_init;
    first_ns = std::min(first_ns, earlier.t_ns);
  }
  result->init.method = estimator.init_method();
  result->init.wait_s = NanosToSeconds(first_ns - first_covered_ns);
}

}  // namespace

void ReportFramesOutsideImu(const EurocDataset& dataset, const FrameSource& source, double max_gap_s,
                            RunResult* result) {
  if (dataset.imu.empty() || source.size() == 0) return;
  const Timestamp imu_begin = dataset.imu.front().t_ns, imu_end = dataset.imu.back().t_ns;
  const double before_s = NanosToSeconds(imu_begin - source.time(0));
  const double after_s = NanosToSeconds(source.time(source.size() - 1) - imu_end);
  for (size_t k = 0; k < source.size(); ++k) {
    if (source.time(k) < imu_begin) ++result->health.frames_before_imu;
    if (source.time(k) > imu_end) ++result->health.frames_after_imu;
  }
  std::ostringstream why;
  if (before_s > max_gap_s) {
    why << result->health.frames_before_imu << " frames (" << before_s << " s) before the first IMU sample ("
        << dataset.imu_file << "); ";
  }
  if (after_s > max_gap_s) {
    why << result->health.frames_after_imu << " frames (" << after_s << " s) after the last IMU sample ("
        << dataset.imu_file << "); ";
  }
  if (why.str().empty()) return;
  const std::string message = why.str() + "they are not estimated (camera/IMU clock offset or truncated IMU?)";
  LOG(WARNING) << message;
  result->problems.push_back(message);
  if (result->status == "ok") result->status = "frames_skipped";
}

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

bool EstimateFrames(const RunRequest& request, const EurocDataset& dataset, FrameSource& source,
                    Estimator& estimator, RunOutput& output, ObservationsCsvWriter* observations,
                    ExtrinsicsProbe* probe, ProgressBar& progress, RunResult* result) {
  const bool init_from_gt = request.config.estimator.init.init == "groundtruth";
  ImuCursor imu{dataset, request.config.estimator.model.max_imu_gap_s};
  Timestamp first_covered_ns = -1;  // the first frame the IMU covers
  for (size_t k = 0; k < source.size(); ++k) {
    const Timestamp t_ns = source.time(k);
    if (dataset.imu.empty() || t_ns < dataset.imu.front().t_ns) continue;  // counted by ReportFramesOutsideImu
    if (t_ns > dataset.imu.back().t_ns) break;
    if (first_covered_ns < 0) first_covered_ns = t_ns;
    if (const int signal = StopSignalOf(request)) {
      Interrupt(k, source.size(), signal, result);
      break;
    }
    try {
      if (auto gap = imu.FeedUpTo(estimator.ImuTimeOf(t_ns), result->frames_estimated > 0, &estimator)) {
        StopAt(k, source.size(), "imu_gap", *gap, result);
        break;
      }
      if (init_from_gt && result->frames_estimated == 0) {
        const InitOptions& init = request.config.estimator.init;
        const std::optional<InitialState> gt = GroundTruthInitialState(
            dataset.groundtruth, dataset.imu, t_ns, request.config.estimator.model.gravity, init.static_window_s);
        if (!gt) {  // frame before the ground-truth span: no state to start from
          ++result->health.frames_waiting_init;
          continue;
        }
        estimator.SetInitialState(*gt);
        if (probe != nullptr) probe->SetInitialState(*gt);
      }
      const StereoFrame frame = source.Frame(k, estimator);
      if (observations != nullptr) observations->Add(frame);
      const FrameEstimate estimate = estimator.ProcessFrame(frame);
      if (estimator.window().health().stopped_solves > 0) {  // its solve was cut short: not written
        Interrupt(k, source.size(), StopSignalOf(request), result);
        break;
      }
      progress.Update(static_cast<std::int64_t>(k + 1));
      if (const std::string problem = InputProblem(source, estimator); !problem.empty()) {
        StopAt(k, source.size(), "bad_input", problem, result);
        break;
      }
      if (estimator.restart_requested()) return true;
      // Both estimators take the front end's one output; a probe that decided is dropped (or ends the pass).
      if (probe != nullptr && probe->running() && probe->Update(frame, dataset.imu, estimator) && probe->applied()) {
        return true;
      }
      if (!estimate.initialized) {
        ++result->health.frames_waiting_init;
        result->init.last_reason = estimator.waiting_reason();
        continue;
      }
      if (result->frames_estimated == 0) AddEarlierEstimates(estimator, first_covered_ns, t_ns, output, result);
      if (Diverged(estimate)) {
        StopAt(k, source.size(), "diverged",
               "estimate diverged at t=" + std::to_string(NanosToSeconds(estimate.t_ns)) + " s (frame " +
                   std::to_string(k) + "): |p| > 10 km, |v| > 100 m/s or not finite",
               result);
        break;
      }
      output.AddFrame(estimate);
      if (request.output_covariance) {
        if (const std::optional<StateCovariance> covariance = estimator.NewestCovariance()) {
          output.AddCovariance(*covariance);
        }
      }
      ++result->frames_estimated;
    } catch (const std::exception& e) {
      StopAt(k, source.size(), "failed",
             "frame " + std::to_string(k) + " (t=" + std::to_string(NanosToSeconds(t_ns)) + " s): " + e.what(),
             result);
      break;
    }
  }
  return false;
}

}  // namespace vio::tools
