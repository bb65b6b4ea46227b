// The estimator's solves of its kept measurements (refinement.h): the offline refinement and the
// extrinsics probe's solve.
#include <cmath>
#include <map>

#include "vio/estimator/estimator.h"

namespace vio {

RefinementReport Estimator::RefineLog(const MeasurementLog& log, Window& whole) const {
  std::map<Timestamp, FrameEstimate> last;
  for (const FrameEstimate& e : LastEstimates()) last[e.t_ns] = e;
  const StartValue start = [&last](const LoggedState& logged, State* s) {
    const auto it = last.find(logged.t_ns);
    if (it == last.end()) return false;
    s->SetPose(it->second.p_w_b, it->second.q_w_b);
    s->SetSpeedBias(it->second.v_w_b, it->second.gyro_bias, it->second.accel_bias);
    return true;
  };
  LandmarkStarts landmarks = log.landmarks;
  for (const auto& [id, landmark] : window_.landmarks()) landmarks[id] = landmark.position();
  whole.SetSolveControl(window_.solve_control());
  return vio::Refine(log, start, landmarks, options_, whole);
}

std::vector<FrameEstimate> Estimator::Refine(RefinementReport* report) const {
  std::vector<FrameEstimate> refined;
  if (!log_ || log_->states.empty()) return refined;
  // Every state and landmark of the run, nothing removed but the observations that do not evaluate at the start.
  Window whole(options_.model, window_.estimated_stereo(), ResidualIndex::kNone);
  *report = RefineLog(*log_, whole);
  if (!report->usable) return refined;
  for (const auto& [id, s] : whole.states()) refined.push_back(EstimateOf(s));
  return refined;
}

ExtrinsicsSolve Estimator::SolveExtrinsics(int stride) const {
  ExtrinsicsSolve solve;
  solve.rig = window_.estimated_stereo();
  if (!log_ || log_->states.empty()) return solve;
  Window whole(options_.model, window_.estimated_stereo(), ResidualIndex::kNone);
  whole.EstimateExtrinsics(options_.model.extrinsics_prior_sigma_deg * M_PI / 180.0,
                           options_.model.extrinsics_prior_sigma_m);
  solve.report = RefineLog(Thinned(*log_, stride), whole);
  if (!solve.report.usable) return solve;
  solve.correction = whole.extrinsic_correction();
  solve.covariance = whole.ExtrinsicCovariance();
  solve.rig = whole.estimated_stereo();
  return solve;
}

}  // namespace vio
