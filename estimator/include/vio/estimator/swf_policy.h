#pragma once
// The sliding window filter SWF(k) (paper §4.1): one state per frame linked by
// an IMU factor; landmarks enter at once (stereo-triangulated) with all their
// observations; Gauss-Newton to convergence (bounded); beyond k states the
// oldest state is marginalized, together with the landmarks no other state
// sees (swf_landmarks=keep, the paper's policy) or with every landmark it sees
// (swf_landmarks=marginalize: the prior stays over states only, cheaper).
// With persistent_landmarks > 0, landmarks observed long enough stay beyond
// the window (persistent_landmarks.h). With local_map_keyframes > 0 the
// states leaving the window join the local map or are dropped (local_map.h):
// nothing is marginalized.
#include "vio/estimator/local_map.h"
#include "vio/estimator/persistent_landmarks.h"
#include "vio/estimator/policy.h"

namespace vio {

class SwfPolicy final : public Policy {
 public:
  explicit SwfPolicy(const EstimatorOptions& options)
      : options_(options), persistent_(options.persistent), local_map_(options) {}
  PolicyTiming Update(const StereoFrame& frame, StateId new_state, Window& window) override;
  /// Logs the long-lived landmarks' counts; the trajectory is the filter's.
  bool Finish(Window& /*window*/) override {
    LogPersistentCounts(persistent_);
    LogLocalMapCounts(local_map_);
    return false;
  }
  const PersistentLandmarks& persistent() const { return persistent_; }
  const LocalMap& local_map() const { return local_map_; }
  std::vector<State> StatesBehindWindow(const Window& window) const override { return local_map_.LastStates(window); }

 private:
  PolicyTiming UpdateWithLocalMap(const StereoFrame& frame, StateId new_state, Window& window);

  EstimatorOptions options_;
  PersistentLandmarks persistent_;
  LocalMap local_map_;
};

}  // namespace vio
