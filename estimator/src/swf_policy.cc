#include "vio/estimator/swf_policy.h"

namespace vio {

PolicyTiming SwfPolicy::Update(const StereoFrame& frame, StateId new_state, Window& window) {
  PolicyTiming timing = AddFrameAndSolve(frame, new_state, options_, window);
  const auto start = std::chrono::steady_clock::now();
  if (static_cast<int>(window.states().size()) > options_.policy.window_size) {
    MarginalizeStateAndItsLandmarks(window.states().begin()->first, options_.policy, window);
  }
  timing.marginalize_ms = MillisecondsSince(start);
  return timing;
}

}  // namespace vio
