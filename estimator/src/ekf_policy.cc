#include "vio/estimator/ekf_policy.h"

#include <chrono>

namespace vio {

PolicyTiming EkfPolicy::Update(const StereoFrame& frame, StateId new_state, Window& window) {
  PolicyTiming timing;
  auto start = std::chrono::steady_clock::now();
  std::vector<StateId> previous;
  for (const auto& [id, state] : window.states()) {
    if (id != new_state) previous.push_back(id);
  }
  window.Marginalize(previous, {});
  timing.marginalize_ms = MillisecondsSince(start);

  start = std::chrono::steady_clock::now();
  AddStereoObservations(frame, new_state, options_.model, window, options_.policy.ekf_max_landmarks);
  timing.build_ms = MillisecondsSince(start);

  start = std::chrono::steady_clock::now();
  const SolveReport report = iterated_ ? window.Solve(options_.solver) : window.TakeSteps(1, options_.solver);
  timing.solver_iterations = report.iterations;
  timing.solve_ms = MillisecondsSince(start);

  if (options_.policy.ekf_landmarks == "marginalize_unseen") {
    start = std::chrono::steady_clock::now();
    std::set<LandmarkId> seen;
    for (const StereoObservation& obs : frame.observations) seen.insert(obs.landmark);
    std::vector<LandmarkId> unseen;
    for (const auto& [id, landmark] : window.landmarks()) {
      if (seen.count(id) == 0) unseen.push_back(id);
    }
    window.Marginalize({}, unseen);
    timing.marginalize_ms += MillisecondsSince(start);
  }
  return timing;
}

}  // namespace vio
