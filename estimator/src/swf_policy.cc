#include "vio/estimator/swf_policy.h"

namespace vio {

PolicyTiming SwfPolicy::Update(const StereoFrame& frame, StateId new_state, Window& window) {
  if (local_map_.enabled()) return UpdateWithLocalMap(frame, new_state, window);
  PolicyTiming timing = AddFrameAndSolve(frame, new_state, options_, window);
  const auto start = std::chrono::steady_clock::now();
  persistent_.Observe(frame);
  std::vector<StateId> leaving;
  if (static_cast<int>(window.states().size()) > options_.policy.window_size) {
    leaving.push_back(window.states().begin()->first);
  }
  const std::vector<LandmarkId> landmarks =
      KeepLongLived(LandmarksLeavingWith(leaving, options_.policy, window), frame.t_ns, window, persistent_);
  window.Marginalize(leaving, landmarks);
  timing.marginalize_ms = MillisecondsSince(start);
  return timing;
}

PolicyTiming SwfPolicy::UpdateWithLocalMap(const StereoFrame& frame, StateId new_state, Window& window) {
  auto start = std::chrono::steady_clock::now();
  std::vector<StateId> parked;
  const StereoFrame gated = local_map_.Prepare(frame, new_state, window, &parked);
  const double prepare_ms = MillisecondsSince(start);
  PolicyTiming timing = AddFrameAndSolve(gated, new_state, options_, window);
  timing.build_ms += prepare_ms;
  start = std::chrono::steady_clock::now();
  local_map_.Slide(window);
  timing.marginalize_ms = MillisecondsSince(start);
  return timing;
}

}  // namespace vio
