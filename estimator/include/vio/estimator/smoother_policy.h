#pragma once
// The incremental smoother: every state and landmark kept, as batch, but each
// frame solved towards the maximum a posteriori estimate from the data so far
// (the online trajectory is written frame by frame). Each frame solves the
// states from the `smoother_active_states`-th newest that observes landmarks on
// (a tracking loss's IMU-only states stay solved until that many tracked frames
// follow them), the landmarks they see and the older states whose pending step
// is large; every other state is held constant, its
// observations summarized in its landmarks' quadratic models
// (frozen_observations.h). The relinearization test (iSAM2's idea on the held
// states): a held state's Gauss-Newton step alone, over the residuals on it at
// the current values (Window::StateStep); above `smoother_relinearize_threshold`
// the state is freed for the frame's solve (its summarized observations taken
// out again) and held again after it (summarized anew at the new values). With
// every state checked and a threshold of zero, each frame is the solve of
// everything so far: batch over the data up to that frame.
#include <cstdint>
#include <limits>
#include <map>
#include <set>
#include <vector>

#include "vio/estimator/frozen_observations.h"
#include "vio/estimator/policy.h"

namespace vio {

class SmootherPolicy final : public Policy {
 public:
  /// Ceres' Levenberg-Marquardt on an id-ordered copy (Window::SolveSparse), as batch's solves.
  explicit SmootherPolicy(const EstimatorOptions& options) : options_(options) { options_.solver.step = "lm"; }
  PolicyTiming Update(const StereoFrame& frame, StateId new_state, Window& window) override;
  /// Logs the relinearization counts; the online estimates are the run's trajectory (false).
  bool Finish(Window& window) override;

  /// States freed by the relinearization test so far [count].
  std::int64_t freed() const { return freed_; }

 private:
  /// The held states to check this frame: the newest held ones, then in turn from the oldest.
  std::vector<StateId> Candidates(const Window& window);
  /// Frees the checked states whose pending step exceeds the threshold.
  void FreeMoved(Window& window);
  void Free(StateId state, Window& window);
  /// Holds every active state older than the newest smoother_active_states that observe landmarks.
  void HoldOld(Window& window);

  EstimatorOptions options_;
  std::set<StateId> active_;  ///< states solved this frame, oldest first
  std::set<StateId> observing_;  ///< the active states that observe landmarks (not a tracking loss's)
  std::map<StateId, std::vector<SummarizedObservation>> held_;  ///< each held state's summarized observations
  FrozenObservations frozen_;
  StateId cursor_{std::numeric_limits<std::int64_t>::min()};   ///< the round of checks goes on after it
  StateId refresh_from_{std::numeric_limits<std::int64_t>::min()};  ///< IMU factors into it and later: checked
  std::int64_t freed_ = 0;
  std::int64_t frames_ = 0;
  std::int64_t checked_ = 0;
  double largest_step_ = 0;  ///< of the checked states [m or rad]
};

}  // namespace vio
