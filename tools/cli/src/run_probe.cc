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

void ExtrinsicsProbe::Start(Estimator& run, bool keep_log) {
  run.KeepMeasurements();
  running_ = true;
  keep_log_ = keep_log;
  start_ns_ = last_ns_ = -1;
  report_.reset();
}

bool ExtrinsicsProbe::Update(const FrameEstimate& estimate, Estimator& run) {
  if (decided()) return true;
  CHECK(running()) << "ExtrinsicsProbe::Update before Start";
  if (!estimate.initialized) return false;
  if (start_ns_ < 0) start_ns_ = estimate.t_ns;
  last_ns_ = estimate.t_ns;
  if (run.searching() || last_ns_ - start_ns_ < SecondsToNanos(model_.extrinsics_probe_s)) return false;
  Decide(run);
  return true;
}

void ExtrinsicsProbe::Finish(Estimator& run) {
  if (decided()) return;
  CHECK(running()) << "ExtrinsicsProbe::Finish before Start";
  Decide(run);
}

void ExtrinsicsProbe::Decide(Estimator& run) {
  running_ = false;
  ExtrinsicsSolve solve;
  try {
    solve = run.SolveExtrinsics(model_.extrinsics_probe_stride);
  } catch (const std::exception& e) {
    LOG(WARNING) << "extrinsics probe: its solve failed: " << e.what() << "; the run goes on without it";
  }
  if (!keep_log_) run.DropMeasurements();
  const Eigen::Matrix<double, 6, 1>& c = solve.correction;
  CalibrationReport::ExtrinsicsProbe report;
  report.duration_s = start_ns_ < 0 ? 0.0 : NanosToSeconds(last_ns_ - start_ns_);
  // In the body: R_b_cl Exp(dtheta) = Exp(R_b_cl dtheta) R_b_cl.
  const Eigen::Matrix3d R_b_cl = run.window().stereo().T_b_cl.linear();
  report.rotation_deg = R_b_cl * c.head<3>() * (180.0 / M_PI);
  report.translation_m = c.tail<3>();
  const std::optional<Eigen::Matrix<double, 6, 6>>& covariance = solve.covariance;
  if (covariance) {
    report.rotation_sigma_deg = LargestSigma(R_b_cl * covariance->topLeftCorner<3, 3>() * R_b_cl.transpose()) * (180.0 / M_PI);
    report.translation_sigma_m = LargestSigma(covariance->bottomRightCorner<3, 3>());
    report.chi2 = c.dot(covariance->ldlt().solve(c));
  }
  const bool large = report.rotation_deg.norm() >= model_.extrinsics_probe_min_deg ||
                     report.translation_m.norm() >= model_.extrinsics_probe_min_m;
  report.applied = report.chi2 && *report.chi2 > kChi2 && large;
  rig_ = solve.rig;
  std::ostringstream what;
  what << std::fixed << std::setprecision(3) << "extrinsics probe after " << report.duration_s << " s ("
       << solve.report.states << " states solved, " << solve.report.iterations << " iterations, "
       << solve.report.seconds << " s): the rig's correction " << report.rotation_deg.norm() << " deg, "
       << report.translation_m.norm() << " m";
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
}

}  // namespace vio::tools
