#pragma once
// `vio run`'s extrinsics probe (docs/calibration.md): the run's first seconds with a correction of
// the camera-IMU extrinsics estimated as a state of the window, then a decision: a correction
// significant against its covariance and large enough to matter starts the run again with the rig
// corrected; any other, the run without the probe.
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

  /// After the estimate of the frame at t_ns (the run initialized): once the searches at
  /// initialization decided, checks the correction's covariance every kCheckS of frame time and
  /// decides when its sigmas are below half the smallest corrections that matter or extrinsics_probe_s
  /// has passed since the first estimate. True once decided.
  bool Update(Timestamp t_ns, Estimator& estimator);
  /// The data ended before the probe decided: it decides with what the window has.
  void Finish(Estimator& estimator);

  bool decided() const { return report_.has_value(); }
  /// Decided and applied: the rig the next pass runs with.
  bool applied() const { return report_ && report_->applied; }
  /// The window's corrected rig at the decision.
  const RectifiedStereo& rig() const { return rig_; }
  const std::optional<CalibrationReport::ExtrinsicsProbe>& report() const { return report_; }

  static constexpr double kCheckS = 1.0;
  /// The chi-square threshold of a 6-dof correction: 0.1 % of a zero correction's draws exceed it.
  static constexpr double kChi2 = 22.46;

 private:
  void Decide(Timestamp t_ns, Estimator& estimator, const std::optional<Eigen::Matrix<double, 6, 6>>& covariance);

  ModelOptions model_;
  Timestamp start_ns_ = -1;       ///< the first estimate's frame
  Timestamp next_check_ns_ = -1;  ///< the next covariance check
  Timestamp last_ns_ = -1;        ///< the last frame seen
  std::optional<CalibrationReport::ExtrinsicsProbe> report_;
  RectifiedStereo rig_;
};

}  // namespace vio::tools
