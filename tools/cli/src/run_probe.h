#pragma once
// `vio run`'s extrinsics probe (docs/calibration.md): a second estimator run in lockstep with the
// run's own over its first seconds, with a correction of the camera-IMU extrinsics as a state of
// its window, then a decision: a correction significant against its covariance and large enough to
// matter starts the run again with the rig corrected; any other drops the probe and the run goes on
// as without it.
#include <memory>
#include <optional>
#include <vector>

#include "vio/cli/run.h"
#include "vio/estimator/estimator.h"

namespace vio::tools {

/// Whether `config` runs the probe: extrinsics_probe_s > 0 and the extrinsics would otherwise be taken
/// as given (not estimated, no local map) by a windowed policy (batch solves the whole sequence at its end).
bool ProbesExtrinsics(const RunConfig& config);

class ExtrinsicsProbe {
 public:
  explicit ExtrinsicsProbe(const ModelOptions& model) : model_(model) {}

  /// Starts the probe for a pass from the first frame, on `rig` (the pass's): its estimator is the
  /// run's `options` with the sliding window whatever the policy, the extrinsics estimated and the
  /// searches at initialization off (the run's own estimator runs them).
  void Start(const EstimatorOptions& options, const ImuCalibration& imu, const RectifiedStereo& rig);
  /// Undecided: the probe's estimator runs (Start was called).
  bool running() const { return estimator_ != nullptr; }
  /// --init=groundtruth: the probe's estimator starts from the same state as the run's.
  void SetInitialState(const InitialState& state);
  /// After the run's estimator (`run`) processed `frame` (its stamp on the camera's clock): the probe's
  /// estimator is given the IMU up to the frame and, before its initialization every frame and then
  /// every extrinsics_probe_stride-th, the frame. Once `run`'s searches at initialization decided, it
  /// checks the correction's covariance every kCheckS of frame time and decides when its sigmas are
  /// below half the smallest corrections that matter or extrinsics_probe_s has passed since its first
  /// estimate. An error in the probe's estimator decides (no covariance: nothing applied). True once decided.
  bool Update(const StereoFrame& frame, const std::vector<ImuSample>& imu, const Estimator& run);
  /// The data ended before the probe decided: it decides with what its window has.
  void Finish();

  bool decided() const { return report_.has_value(); }
  /// Decided and applied: the rig the next pass runs with.
  bool applied() const { return report_ && report_->applied; }
  /// The probe's corrected rig at the decision.
  const RectifiedStereo& rig() const { return rig_; }
  const std::optional<CalibrationReport::ExtrinsicsProbe>& report() const { return report_; }

  static constexpr double kCheckS = 1.0;
  /// The chi-square threshold of a 6-dof correction: 0.1 % of a zero correction's draws exceed it.
  static constexpr double kChi2 = 22.46;

 private:
  /// Gives the probe's estimator the frame (and the IMU up to it); false when it skips the frame.
  bool Process(const StereoFrame& frame, const std::vector<ImuSample>& imu);
  /// Decides and drops the estimator.
  void Decide(Timestamp t_ns, const std::optional<Eigen::Matrix<double, 6, 6>>& covariance);

  ModelOptions model_;
  std::unique_ptr<Estimator> estimator_;  ///< while undecided
  size_t next_imu_ = 0;           ///< the next IMU sample to give it
  std::int64_t frames_since_init_ = 0;  ///< frames since its first estimate, given or skipped
  Timestamp start_ns_ = -1;       ///< its first estimate's frame
  Timestamp next_check_ns_ = -1;  ///< the next covariance check
  Timestamp last_ns_ = -1;        ///< the last frame it estimated
  std::optional<CalibrationReport::ExtrinsicsProbe> report_;
  RectifiedStereo rig_;
};

}  // namespace vio::tools
