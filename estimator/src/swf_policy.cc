#include "vio/estimator/swf_policy.h"

#include <chrono>

namespace vio {
PolicyTiming SwfPolicy::Update(const StereoFrame& frame, StateId new_state, Window& window) {
  PolicyTiming timing;
  auto start = std::chrono::steady_clock::now();
  AddStereoObservations(frame, new_state, options_.model, window);
  window.RefreshImuFactors(options_.model.reintegrate_bias_threshold);
  timing.build_ms = MillisecondsSince(start);

  start = std::chrono::steady_clock::now();
  timing.solver_iterations = window.Solve(options_.solver).iterations;
  timing.solve_ms = MillisecondsSince(start);

  start = std::chrono::steady_clock::now();
  if (static_cast<int>(window.states().size()) > options_.policy.window_size) MarginalizeOldest(window);
  timing.marginalize_ms = MillisecondsSince(start);
  return timing;
}

void SwfPolicy::MarginalizeOldest(Window& window) const {
  const std::vector<StateId> leaving = {window.states().begin()->first};
  const std::vector<LandmarkId> landmarks = options_.policy.swf_landmarks == "keep"
                                                ? LandmarksOnlySeenFrom(window, leaving)
                                                : LandmarksSeenFrom(window, leaving);
  window.Marginalize(leaving, landmarks);
}

}  // namespace vio
