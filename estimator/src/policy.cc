#include "vio/estimator/policy.h"

#include <stdexcept>

#include "vio/estimator/pose_manifold.h"
#include "vio/estimator/stereo_geometry.h"
#include "vio/estimator/batch_policy.h"
#include "vio/estimator/ekf_policy.h"
#include "vio/estimator/keyframe_policy.h"
#include "vio/estimator/msckf_policy.h"
#include "vio/estimator/smoother_policy.h"
#include "vio/estimator/swf_policy.h"

namespace vio {

std::unique_ptr<Policy> MakePolicy(const EstimatorOptions& options) {
  const std::string& name = options.policy.policy;
  if (name == "swf") return std::make_unique<SwfPolicy>(options);
  if (name == "keyframe") return std::make_unique<KeyframePolicy>(options);
  if (name == "batch") return std::make_unique<BatchPolicy>(options);
  if (name == "smoother") return std::make_unique<SmootherPolicy>(options);
  if (name == "msckf") return std::make_unique<MsckfPolicy>(options, options.msckf.msckf_gn_steps);
  if (name == "fixed_lag") return std::make_unique<MsckfPolicy>(options, std::nullopt);
  if (name == "ekf" || name == "iekf") return std::make_unique<EkfPolicy>(options, name == "iekf");
  throw std::invalid_argument("unknown policy '" + name + "'");
}

int AddStereoObservations(const StereoFrame& frame, StateId state_id, const ModelOptions& model, Window& window,
                          int max_landmarks) {
  const State& s = window.state(state_id);
  const Eigen::Isometry3d T_w_b = Eigen::Translation3d(s.p_w_b()) * s.q_w_b();
  const Eigen::Isometry3d T_w_cl = T_w_b * window.estimated_stereo().T_b_cl;
  int added = 0;
  for (const StereoObservation& obs : frame.observations) {
    if (!window.HasLandmark(obs.landmark)) {
      if (max_landmarks > 0 && static_cast<int>(window.landmarks().size()) >= max_landmarks) continue;
      const std::optional<Eigen::Vector3d> p_cl =
          TriangulateRectified(obs.z_px, window.estimated_stereo(), model.min_disparity_px);
      if (!p_cl || p_cl->z() > model.max_depth_m) continue;
      window.AddLandmark(obs.landmark, T_w_cl * *p_cl);
      ++added;
    }
    window.AddObservation(state_id, obs.landmark, obs.z_px);
  }
  return added;
}

void AddToKeptProblem(const StereoFrame& frame, StateId state, const ModelOptions& model, Window& window) {
  for (const StereoObservation& obs : frame.observations) {
    if (window.HasLandmark(obs.landmark)) window.SetLandmarkConstant(obs.landmark, false);
  }
  AddStereoObservations(frame, state, model, window);
}

PolicyTiming AddFrameAndSolve(const StereoFrame& frame, StateId state, const EstimatorOptions& options,
                              Window& window) {
  PolicyTiming timing;
  auto start = std::chrono::steady_clock::now();
  AddStereoObservations(frame, state, options.model, window);
  window.RefreshImuFactors(options.model.reintegrate_bias_threshold);
  timing.build_ms = MillisecondsSince(start);
  start = std::chrono::steady_clock::now();
  timing.solver_iterations = window.Solve(options.solver).iterations;
  timing.solve_ms = MillisecondsSince(start);
  return timing;
}

std::vector<LandmarkId> LandmarksLeavingWith(const std::vector<StateId>& leaving, const PolicyOptions& options,
                                             const Window& window) {
  return options.swf_landmarks == "keep" ? LandmarksOnlySeenFrom(window, leaving) : LandmarksSeenFrom(window, leaving);
}

void MarginalizeStateAndItsLandmarks(StateId state, const PolicyOptions& options, Window& window) {
  const std::vector<StateId> leaving = {state};
  window.Marginalize(leaving, LandmarksLeavingWith(leaving, options, window));
}

std::vector<LandmarkId> LandmarksOnlySeenFrom(const Window& window, const std::vector<StateId>& leaving) {
  std::vector<LandmarkId> out;
  for (const auto& [id, landmark] : window.landmarks()) {
    bool only = !landmark.observed_from.empty();
    for (StateId observer : landmark.observed_from) {
      only = only && std::find(leaving.begin(), leaving.end(), observer) != leaving.end();
    }
    if (only) out.push_back(id);
  }
  return out;
}

std::vector<LandmarkId> LandmarksSeenFrom(const Window& window, const std::vector<StateId>& states) {
  std::vector<LandmarkId> out;
  for (const auto& [id, landmark] : window.landmarks()) {
    for (StateId s : states) {
      if (landmark.observed_from.count(s)) {
        out.push_back(id);
        break;
      }
    }
  }
  return out;
}

}  // namespace vio
