#pragma once
// Full batch (paper §4.4, graph SLAM / bundle adjustment): no
// marginalization. Every state and landmark stays; a landmark seen again is
// the same variable. While the data streams in, the recent states are solved
// every few frames with the states older than the window (and landmarks only
// they see) held constant, the frozen states' observations summarized per
// landmark (frozen_observations.h); after the last frame everything is freed and
// solved together (SolveWhole: sparse Cholesky of the whole system, segments
// of states with the landmarks only they see eliminated first, on a copy laid
// out by id): the offline reference and the accuracy floor of the online
// policies.
#include <cstdint>
#include <limits>
#include <set>

#include "vio/estimator/frozen_observations.h"
#include "vio/estimator/policy.h"

namespace vio {

class BatchPolicy final : public Policy {
 public:
  /// Always Ceres' Levenberg-Marquardt (Window::SolveSparse): the whole
  /// sequence is one sparse problem, beyond the window's dense Gauss-Newton.
  explicit BatchPolicy(const EstimatorOptions& options) : options_(options) { options_.solver.step = "lm"; }
  PolicyTiming Update(const StereoFrame& frame, StateId new_state, Window& window) override;
  bool Finish(Window& window) override;

 private:
  void FreezeOld(Window& window);

  EstimatorOptions options_;
  std::set<StateId> active_;  ///< states not yet frozen, oldest first
  StateId refresh_from_{std::numeric_limits<std::int64_t>::min()};  ///< IMU factors into it and later: checked
  FrozenObservations frozen_;  ///< the frozen states' observations, for the periodic solves
  int frames_ = 0;
};

}  // namespace vio
