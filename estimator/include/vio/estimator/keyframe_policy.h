#pragma once
// Keyframe window, OKVIS-like (paper §4.4): the last few frames form a
// temporal window; a frame is a keyframe when it shares too few landmarks
// with the last keyframe. When a frame leaves the temporal window it stays if
// it is a keyframe and is DROPPED otherwise (its observations go, its IMU
// factors merge into one); beyond `window_size` keyframes the oldest keyframe
// is marginalized like SWF's oldest state. Keyframes may be arbitrarily
// spaced in time, so the window spans more motion for the same cost.
#include <set>

#include "vio/estimator/policy.h"

namespace vio {

class KeyframePolicy final : public Policy {
 public:
  explicit KeyframePolicy(const EstimatorOptions& options) : options_(options) {}
  PolicyTiming Update(const StereoFrame& frame, StateId new_state, Window& window) override;

 private:
  bool IsNewKeyframe(const StereoFrame& frame, const Window& window) const;
  void SlideTemporalWindow(Window& window);
  void MarginalizeOldestKeyframe(Window& window);

  EstimatorOptions options_;
  std::set<StateId> keyframes_;
  std::set<LandmarkId> last_keyframe_landmarks_;
};

}  // namespace vio
