#pragma once
// The sliding window filter SWF(k) (paper §4.1): one state per frame linked by
// an IMU factor; landmarks enter at once (stereo-triangulated) with all their
// observations; Gauss-Newton to convergence (bounded); beyond k states the
// oldest state is marginalized, together with the landmarks no other state
// sees (swf_landmarks=keep, the paper's policy) or with every landmark it sees
// (swf_landmarks=marginalize: the prior stays over states only, cheaper).
// With persistent_landmarks > 0, landmarks observed long enough stay beyond
// the window (persistent_landmarks.h).
#include "vio/estimator/persistent_landmarks.h"
#include "vio/estimator/policy.h"

namespace vio {

class SwfPolicy final : public Policy {
 public:
  explicit SwfPolicy(const EstimatorOptions& options) : options_(options), persistent_(options.persistent) {}
  PolicyTiming Update(const StereoFrame& frame, StateId new_state, Window& window) override;
  /// Logs the long-lived landmarks' counts; the trajectory is the filter's.
  bool Finish(Window& /*window*/) override {
    LogPersistentCounts(persistent_);
    return false;
  }
  const PersistentLandmarks& persistent() const { return persistent_; }

 private:
  EstimatorOptions options_;
  PersistentLandmarks persistent_;
};

}  // namespace vio
