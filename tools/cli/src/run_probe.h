#pragma once
// `vio run`'s extrinsics probe (docs/calibration.md): the run's estimator keeps what it is given over
// its first seconds (Estimator::KeepMeasurements), then one solve of that stretch with a correction of
// the camera-IMU extrinsics as a state (Estimator::SolveExtrinsics) decides: a correction significant
// against its covariance and large enough to matter starts the run again with the rig corrected; any
// other leaves the run as it is, as without the probe.
#include <optional>

#include "vio/cli/run.h"
#include "vio/estimator/estimator.h"

namespace vio::tools {

/// Whether `config` runs the probe: extrinsics_probe_s > 0 and the extrinsics would otherwise be taken
/// as given (not estimated, no local map) by a windowed policy (batch solves the whole sequence at its end).
bool ProbesExtrinsics(const RunConfig& config);

class ExtrinsicsProbe {
 public:
  explicit ExtrinsicsProbe(const ModelOptions& model) : model_(model) {}

  /// Starts the probe for a pass from the first frame: `run` keeps its measurements from now on.
  /// `keep_log`: the run refines its trajectory at its end, so they stay kept after the decision
  /// (else they are dropped then).
  void Start(Estimator& run, bool keep_log);
  /// Started and undecided.
  bool running() const { return running_; }
  /// After `run` processed a frame (`estimate`, its stamp on the camera's clock): once `run`'s searches
  /// at initialization decided and extrinsics_probe_s of frames have passed since its first estimate,
  /// the solve decides. True once decided.
  bool Update(const FrameEstimate& estimate, Estimator& run);
  /// The data ended before the probe decided: it decides with what was kept.
  void Finish(Estimator& run);

  bool decided() const { return report_.has_value(); }
  /// Decided and applied: the rig the next pass runs with.
  bool applied() const { return report_ && report_->applied; }
  /// The corrected rig at the decision.
  const RectifiedStereo& rig() const { return rig_; }
  const std::optional<CalibrationReport::ExtrinsicsProbe>& report() const { return report_; }

  /// The chi-square threshold of a 6-dof correction: 0.1 % of a zero correction's draws exceed it.
  static constexpr double kChi2 = 22.46;

 private:
  /// Solves, decides and ends the keeping of measurements unless `keep_log_`.
  void Decide(Estimator& run);

  ModelOptions model_;
  bool running_ = false;
  bool keep_log_ = false;
  Timestamp start_ns_ = -1;  ///< the run's first estimate's frame
  Timestamp last_ns_ = -1;   ///< the last frame it estimated
  std::optional<CalibrationReport::ExtrinsicsProbe> report_;
  RectifiedStereo rig_;
};

}  // namespace vio::tools
