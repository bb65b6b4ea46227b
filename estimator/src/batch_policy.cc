#include "vio/estimator/batch_policy.h"

#include <algorithm>
#include <chrono>

#include <glog/logging.h>

#include "vio/estimator/refinement.h"

namespace vio {
PolicyTiming BatchPolicy::Update(const StereoFrame& frame, StateId new_state, Window& window) {
  PolicyTiming timing;
  auto start = std::chrono::steady_clock::now();
  active_.insert(new_state);
  AddToKeptProblem(frame, new_state, options_.model, window);
  // A frozen state's bias no longer moves: its IMU factor was last checked by the refresh after
  // the solve it froze at.
  window.RefreshImuFactors(options_.model.reintegrate_bias_threshold, refresh_from_);
  refresh_from_ = *active_.begin();
  timing.build_ms = MillisecondsSince(start);

  if (++frames_ % std::max(1, options_.batch.batch_solve_every) != 0) return timing;
  start = std::chrono::steady_clock::now();
  timing.solver_iterations = window.SolveSparse(options_.solver, frozen_).iterations;
  timing.solve_ms = MillisecondsSince(start);

  start = std::chrono::steady_clock::now();
  FreezeOld(window);
  timing.marginalize_ms = MillisecondsSince(start);
  return timing;
}

// Freezes the states that left the active window and the landmarks no
// active state sees; the frozen states' observations are summarized first
// (frozen_observations.h), at the values the last solve left.
void BatchPolicy::FreezeOld(Window& window) {
  while (static_cast<int>(active_.size()) > options_.policy.window_size) {
    const StateId oldest = *active_.begin();
    active_.erase(active_.begin());
    window.SummarizeObservationsOf(oldest, frozen_);
    window.SetStateConstant(oldest, true);
    // Frozen states keep their errors: fitted against them the calibration would absorb those
    // errors (the time offset on a synthetic flight: +2.5 ms on near-noiseless data), so it is held
    // from the first freeze until the final solve.
    window.SetCalibrationConstant(true);
    for (const auto& [id, landmark] : window.landmarks()) {
      if (!landmark.observed_from.count(oldest)) continue;
      // The active states are the newest: the landmark's newest observer decides.
      const bool seen_by_active = active_.count(*landmark.observed_from.rbegin()) > 0;
      if (!seen_by_active) window.SetLandmarkConstant(id, true);
    }
  }
}

bool BatchPolicy::Finish(Window& window) {
  for (const auto& [id, state] : window.states()) window.SetStateConstant(id, false);
  for (const auto& [id, landmark] : window.landmarks()) window.SetLandmarkConstant(id, false);
  window.SetCalibrationConstant(false);
  if (frozen_.skipped > 0) {
    LOG(WARNING) << "batch: " << frozen_.skipped << " observations did not evaluate when their state froze and were "
                 << "left out of the periodic solves";
  }
  frozen_ = FrozenObservations();
  const SolveReport report = SolveWhole(window, options_);
  LOG(INFO) << "batch: final solve over " << window.states().size() << " states and " << window.landmarks().size()
            << " landmarks, " << report.iterations << " iterations, cost " << report.initial_cost << " -> "
            << report.final_cost;
  return true;
}

}  // namespace vio
