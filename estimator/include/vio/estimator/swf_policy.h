#pragma once
// The sliding window filter SWF(k) (paper §4.1): one state per frame linked by
// an IMU factor; landmarks enter at once (stereo-triangulated) with all their
// observations; Gauss-Newton to convergence (bounded); beyond k states the
// oldest state is marginalized, together with the landmarks no other state
// sees (swf_landmarks=keep, the paper's policy) or with every landmark it sees
// (swf_landmarks=marginalize: the prior stays over states only, cheaper).
#include "vio/estimator/policy.h"

namespace vio {

class SwfPolicy final : public Policy {
 public:
  explicit SwfPolicy(const EstimatorOptions& options) : options_(options) {}
  PolicyTiming Update(const StereoFrame& frame, StateId new_state, Window& window) override;

 private:
  EstimatorOptions options_;
};

}  // namespace vio
