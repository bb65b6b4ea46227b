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

bool ExtrinsicsProbe::Update(Timestamp t_ns, Estimator& estimator) {
  if (decided()) return true;
  if (start_ns_ < 0) start_ns_ = next_check_ns_ = t_ns;
  last_ns_ = t_ns;
  if (estimator.searching() || t_ns < next_check_ns_) return false;
  next_check_ns_ = t_ns + SecondsToNanos(kCheckS);
  const std::optional<Eigen::Matrix<double, 6, 6>> covariance = estimator.ExtrinsicCovariance();
  const bool time_up = t_ns - start_ns_ >= SecondsToNanos(model_.extrinsics_probe_s);
  const bool settled =
      covariance && LargestSigma(covariance->topLeftCorner<3, 3>()) < 0.5 * model_.extrinsics_probe_min_deg * M_PI / 180.0 &&
      LargestSigma(covariance->bottomRightCorner<3, 3>()) < 0.5 * model_.extrinsics_probe_min_m;
  if (!time_up && !settled) return false;
  Decide(t_ns, estimator, covariance);
  return true;
}

void ExtrinsicsProbe::Finish(Estimator& estimator) {
  if (decided()) return;
  // Never initialized: no window to ask.
  Decide(last_ns_, estimator, start_ns_ < 0 ? std::nullopt : estimator.ExtrinsicCovariance());
}

void ExtrinsicsProbe::Decide(Timestamp t_ns, Estimator& estimator,
                             const std::optional<Eigen::Matrix<double, 6, 6>>& covariance) {
  const Window& window = estimator.window();
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
              << " to apply); starting again from the first frame with sensor.yaml's rig";
  }
  report_ = report;
}

}  // namespace vio::tools
