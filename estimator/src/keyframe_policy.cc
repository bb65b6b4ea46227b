#include "vio/estimator/keyframe_policy.h"

#include <chrono>
#include <iterator>

namespace vio {
PolicyTiming KeyframePolicy::Update(const StereoFrame& frame, StateId new_state, Window& window) {
  if (IsNewKeyframe(frame, window)) {
    keyframes_.insert(new_state);
    last_keyframe_landmarks_.clear();
    for (const StereoObservation& obs : frame.observations) last_keyframe_landmarks_.insert(obs.landmark);
  }
  PolicyTiming timing = AddFrameAndSolve(frame, new_state, options_, window);
  const auto start = std::chrono::steady_clock::now();
  SlideTemporalWindow(window);
  if (static_cast<int>(keyframes_.size()) > options_.policy.window_size) MarginalizeOldestKeyframe(window);
  timing.marginalize_ms = MillisecondsSince(start);
  return timing;
}

// A keyframe when less than keyframe_overlap of the frame's landmarks were
// seen by the last keyframe (always for the first frame).
bool KeyframePolicy::IsNewKeyframe(const StereoFrame& frame, const Window& window) const {
  if (keyframes_.empty() || window.states().size() <= 1) return true;
  if (frame.observations.empty()) return false;
  int shared = 0;
  for (const StereoObservation& obs : frame.observations) shared += last_keyframe_landmarks_.count(obs.landmark);
  return shared < options_.policy.keyframe_overlap * static_cast<double>(frame.observations.size());
}

// The newest non-keyframe beyond the temporal window leaves: dropped, or
// marginalized when a prior already involves it.
void KeyframePolicy::SlideTemporalWindow(Window& window) {
  const int temporal = options_.policy.keyframe_temporal_window;
  if (static_cast<int>(window.states().size()) <= temporal) return;
  auto leaving = std::prev(window.states().end(), temporal + 1);
  const StateId id = leaving->first;
  if (keyframes_.count(id) || leaving == window.states().begin()) return;
  if (window.IsInPrior(id)) {
    MarginalizeStateAndItsLandmarks(id, options_.policy, window);
  } else {
    window.DropState(id);
  }
}

void KeyframePolicy::MarginalizeOldestKeyframe(Window& window) {
  const StateId oldest = *keyframes_.begin();
  keyframes_.erase(keyframes_.begin());
  MarginalizeStateAndItsLandmarks(oldest, options_.policy, window);
}

}  // namespace vio
