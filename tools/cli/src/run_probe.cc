#include "run_probe.h"

#include <cmath>
#include <iomanip>
#include <sstream>

#include <Eigen/Cholesky>
#include <glog/logging.h>

#include "run_calibration.h"

namespace vio::tools {

bool ProbesExtrinsics(const RunConfig& config) {
  const EstimatorOptions& estimator = config.estimator;
  return estimator.model.extrinsics_probe_s > 0 && !estimator.model.estimate_extrinsics &&
         estimator.local_map.local_map_keyframes == 0 && estimator.policy.policy != "batch";
}

void ExtrinsicsProbe::Start(const EstimatorOptions& options, const ImuCalibration& imu, const RectifiedStereo& rig) {
  EstimatorOptions probe = options;
  // The sliding window whatever the run's policy: MSCKF's estimate of the translation was the worse
  // (docs/calibration.md).
  probe.policy.policy = "swf";
  probe.model.estimate_extrinsics = true;
  probe.model.time_offset_search_ms = 0;
  probe.model.extrinsics_rotation_search = false;
  estimator_ = std::make_unique<Estimator>(probe, imu, rig);
  next_imu_ = 0;
  frames_since_init_ = 0;
  start_ns_ = next_check_ns_ = last_ns_ = -1;
  report_.reset();
}

void ExtrinsicsProbe::SetInitialState(const InitialState& state) {
  if (running()) estimator_->SetInitialState(state);
}

bool ExtrinsicsProbe::Process(const StereoFrame& frame, const std::vector<ImuSample>& imu) {
  const Timestamp imu_t_ns = estimator_->ImuTimeOf(frame.t_ns);
  while (next_imu_ < imu.size() && (next_imu_ == 0 || imu[next_imu_ - 1].t_ns < imu_t_ns)) {
    estimator_->AddImu(imu[next_imu_++]);
  }
  if (start_ns_ >= 0 && ++frames_since_init_ % model_.extrinsics_probe_stride != 0) return false;
  const FrameEstimate estimate = estimator_->ProcessFrame(frame);
  if (!estimate.initialized) return false;
  if (!estimate.p_w_b.allFinite() || !estimate.v_w_b.allFinite() || estimate.p_w_b.norm() > 1e4 ||
      estimate.v_w_b.norm() > 100) {
    throw std::runtime_error("its estimate diverged at t=" + std::to_string(NanosToSeconds(frame.t_ns)) + " s");
  }
  if (start_ns_ < 0) start_ns_ = next_check_ns_ = frame.t_ns;
  last_ns_ = frame.t_ns;
  return true;
}

bool ExtrinsicsProbe::Update(const StereoFrame& frame, const std::vector<ImuSample>& imu, const Estimator& run) {
  if (decided()) return true;
  CHECK(running()) << "ExtrinsicsProbe::Update before Start";
  try {
    if (!Process(frame, imu)) return false;
  } catch (const std::exception& e) {
    LOG(WARNING) << "extrinsics probe: " << e.what() << "; the run goes on without it";
    Decide(last_ns_, std::nullopt);
    return true;
  }
  if (run.searching() || last_ns_ < next_check_ns_) return false;
  next_check_ns_ = last_ns_ + SecondsToNanos(kCheckS);
  const std::optional<Eigen::Matrix<double, 6, 6>> covariance = estimator_->ExtrinsicCovariance();
  const bool time_up = last_ns_ - start_ns_ >= SecondsToNanos(model_.extrinsics_probe_s);
  const bool settled =
      covariance && LargestSigma(covariance->topLeftCorner<3, 3>()) < 0.5 * model_.extrinsics_probe_min_deg * M_PI / 180.0 &&
      LargestSigma(covariance->bottomRightCorner<3, 3>()) < 0.5 * model_.extrinsics_probe_min_m;
  if (!time_up && !settled) return false;
  Decide(last_ns_, covariance);
  return true;
}

void ExtrinsicsProbe::Finish() {
  if (decided()) return;
  CHECK(running()) << "ExtrinsicsProbe::Finish before Start";
  // Never initialized: no window to ask.
  Decide(last_ns_, start_ns_ < 0 ? std::nullopt : estimator_->ExtrinsicCovariance());
}

void ExtrinsicsProbe::Decide(Timestamp t_ns, const std::optional<Eigen::Matrix<double, 6, 6>>& covariance) {
  const Window& window = estimator_->window();
  const Eigen::Matrix<double, 6, 1> c = window.extrinsic_correction();
  CalibrationReport::ExtrinsicsProbe report;
  report.duration_s = start_ns_ < 0 ? 0.0 : NanosToSeconds(t_ns - start_ns_);
  // In the body: R_b_cl Exp(dtheta) = Exp(R_b_cl dtheta) R_b_cl.
  const Eigen::Matrix3d R_b_cl = window.stereo().T_b_cl.linear();
  report.rotation_deg = R_b_cl * c.head<3>() * (180.0 / M_PI);
  report.translation_m = c.tail<3>();
  if (covariance) {
    report.rotation_sigma_deg = LargestSigma(R_b_cl * covariance->topLeftCorner<3, 3>() * R_b_cl.transpose()) * (180.0 / M_PI);
    report.translation_sigma_m = LargestSigma(covariance->bottomRightCorner<3, 3>());
    report.chi2 = c.dot(covariance->ldlt().solve(c));
  }
  const bool large = report.rotation_deg.norm() >= model_.extrinsics_probe_min_deg ||
                     report.translation_m.norm() >= model_.extrinsics_probe_min_m;
  report.applied = report.chi2 && *report.chi2 > kChi2 && large;
  rig_ = window.estimated_stereo();
  std::ostringstream what;
  what << std::fixed << std::setprecision(3) << "extrinsics probe after " << report.duration_s
       << " s: the rig's correction " << report.rotation_deg.norm() << " deg, " << report.translation_m.norm() << " m";
  if (covariance) {
    what << " (sigmas " << *report.rotation_sigma_deg << " deg, " << *report.translation_sigma_m << " m; chi2 "
         << std::setprecision(1) << *report.chi2 << ")";
  } else {
    what << " (no covariance)";
  }
  if (report.applied) {
    LOG(WARNING) << what.str() << ": significant; starting again from the first frame with the rig corrected by it";
  } else {
    LOG(INFO) << what.str() << ": not significant (chi2 above " << kChi2 << " and at least extrinsics_probe_min_deg "
              << model_.extrinsics_probe_min_deg << " or extrinsics_probe_min_m " << model_.extrinsics_probe_min_m
              << " to apply); the run goes on with sensor.yaml's rig";
  }
  report_ = report;
  estimator_.reset();
}

}  // namespace vio::tools
