#pragma once
// EKF-SLAM as optimization (paper Algorithm 3, Theorems 4.3.1-4.3.3). Each
// frame, in the paper's order:
//   propagation  the new state x_t (IMU prediction, linked to x_{t-1} by its
//                IMU factor) is added and x_{t-1} is marginalized at once
//                (Theorem 4.3.3); every landmark stays, now in the prior;
//   augmentation the frame's new landmarks enter, stereo-triangulated from
//                x_t (one GN step on c_EKF,t,1 starts from this zero-residual
//                point, Theorem 4.3.1);
//   update       the frame's observations enter and one Gauss-Newton step is
//                taken on the whole cost (Theorem 4.3.2); the iterated EKF
//                takes steps to convergence (at most max_iterations).
// With ekf_landmarks=keep (the paper) the landmarks stay forever: the prior
// grows with the map and each step costs O(map^3). marginalize_unseen (the
// default) marginalizes, after the update, the landmarks the frame did not
// observe (in covariance form: deleting them from the state).
// ekf_max_landmarks bounds the map: new landmarks enter only while it has
// room (a KLT front end sees 150-300 per frame: without the bound the dense
// step over all of them is slower than real time).
#include <set>

#include "vio/estimator/policy.h"

namespace vio {

class EkfPolicy final : public Policy {
 public:
  /// `iterated`: Gauss-Newton to convergence instead of one step.
  EkfPolicy(const EstimatorOptions& options, bool iterated) : options_(options), iterated_(iterated) {}
  PolicyTiming Update(const StereoFrame& frame, StateId new_state, Window& window) override;

 private:
  EstimatorOptions options_;
  bool iterated_;
};

}  // namespace vio
