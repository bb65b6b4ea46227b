#include "vio/estimator/smoother_policy.h"

#include <algorithm>
#include <chrono>

#include <glog/logging.h>

namespace vio {

PolicyTiming SmootherPolicy::Update(const StereoFrame& frame, StateId new_state, Window& window) {
  PolicyTiming timing;
  auto start = std::chrono::steady_clock::now();
  active_.insert(new_state);
  AddToKeptProblem(frame, new_state, options_.model, window);
  if (!window.ObservationsOf(new_state).empty()) observing_.insert(new_state);
  FreeMoved(window);
  window.RefreshImuFactors(options_.model.reintegrate_bias_threshold, std::min(refresh_from_, *active_.begin()));
  timing.build_ms = MillisecondsSince(start);

  start = std::chrono::steady_clock::now();
  SolverOptions solver = options_.solver;
  // Many states solved (a full solve): the whole system by sparse Cholesky, segments first.
  if (static_cast<int>(active_.size()) > 2 * options_.smoother.smoother_active_states) solver.linear_solver = "sparse_full";
  const SolveReport report = window.SolveSparse(solver, frozen_);
  timing.solver_iterations = report.iterations;
  VLOG(1) << "smoother: " << active_.size() << " states solved, cost " << report.initial_cost << " -> "
          << report.final_cost << " in " << report.iterations << " iterations";
  timing.solve_ms = MillisecondsSince(start);

  start = std::chrono::steady_clock::now();
  refresh_from_ = *active_.begin();  // the next frame re-checks the IMU factors of what moved
  HoldOld(window);
  timing.marginalize_ms = MillisecondsSince(start);
  return timing;
}

std::vector<StateId> SmootherPolicy::Candidates(const Window& window) {
  std::vector<StateId> out;
  const auto& states = window.states();
  const auto held_end = states.lower_bound(*active_.begin());
  const int checks = options_.smoother.smoother_checks_per_frame;
  if (checks == 0) {
    for (auto it = states.begin(); it != held_end; ++it) out.push_back(it->first);
    return out;
  }
  // The newest held states first: a solve moves most what it was tied to last.
  int newest = 0;
  for (auto it = held_end; it != states.begin() && newest < (checks + 1) / 2; ++newest) out.push_back((--it)->first);
  const StateId newest_checked = out.empty() ? StateId(std::numeric_limits<std::int64_t>::max()) : out.back();
  for (int k = static_cast<int>(out.size()); k < checks; ++k) {
    auto it = states.upper_bound(cursor_);
    if (it == held_end || it == states.end() || !(it->first < newest_checked)) it = states.begin();
    if (it == held_end || !(it->first < newest_checked)) break;  // nothing older left to check
    cursor_ = it->first;
    if (std::find(out.begin(), out.end(), cursor_) != out.end()) break;
    out.push_back(cursor_);
  }
  std::sort(out.begin(), out.end());
  return out;
}

void SmootherPolicy::FreeMoved(Window& window) {
  const int full_every = options_.smoother.smoother_full_every;
  if (full_every > 0 && ++frames_ % full_every == 0) {
    while (!held_.empty()) Free(held_.begin()->first, window);
    return;
  }
  const double threshold = options_.smoother.smoother_relinearize_threshold;
  for (const StateId id : Candidates(window)) {
    if (!held_.count(id)) continue;
    const Eigen::Matrix<double, 15, 1> step = window.StateStep(id);
    const double size = std::max(step.head<3>().norm(), step.segment<3>(3).norm());
    ++checked_;
    largest_step_ = std::max(largest_step_, size);
    VLOG(2) << "smoother: state " << id.value << " pending step " << size;
    if (size > threshold) Free(id, window);
  }
}

// Its observations leave the summaries (the solve has their residuals again); the
// landmarks it sees are solved with it.
void SmootherPolicy::Free(StateId id, Window& window) {
  auto it = held_.find(id);
  for (const SummarizedObservation& part : it->second) RemoveFromSummary(part, frozen_);
  held_.erase(it);
  if (!window.ObservationsOf(id).empty()) observing_.insert(id);
  window.SetStateConstant(id, false);
  for (const auto& [landmark, z] : window.ObservationsOf(id)) window.SetLandmarkConstant(landmark, false);
  active_.insert(id);
  ++freed_;
}

// A state is held once `smoother_active_states` newer states observe landmarks: the IMU-only
// states of a tracking loss stay solved until that many tracked frames follow it, so the stretch
// the IMU bridged bends to fit the frames on both ends (held, it would keep its dead reckoning).
void SmootherPolicy::HoldOld(Window& window) {
  std::set<LandmarkId> seen;
  const int keep = options_.smoother.smoother_active_states;
  const auto newer_observing = [this] {
    return static_cast<int>(observing_.size()) - static_cast<int>(observing_.count(*active_.begin()));
  };
  while (static_cast<int>(active_.size()) > keep && newer_observing() >= keep) {
    const StateId oldest = *active_.begin();
    active_.erase(active_.begin());
    observing_.erase(oldest);
    std::vector<SummarizedObservation>& parts = held_[oldest];
    window.SummarizeObservationsOf(oldest, frozen_, &parts);
    window.SetStateConstant(oldest, true);
    // As batch's: the calibration is held once states are (their errors would bias it).
    window.SetCalibrationConstant(true);
    for (const auto& [landmark, z] : window.ObservationsOf(oldest)) seen.insert(landmark);
  }
  // The active states are the newest: a landmark's newest observer decides.
  for (const LandmarkId id : seen) {
    const bool seen_by_active = active_.count(*window.landmark(id).observed_from.rbegin()) > 0;
    if (!seen_by_active) window.SetLandmarkConstant(id, true);
  }
}

bool SmootherPolicy::Finish(Window& window) {
  LOG(INFO) << "smoother: " << window.states().size() << " states, " << checked_ << " pending steps checked (largest "
            << largest_step_ << "), " << freed_ << " states freed by them";
  return false;
}

}  // namespace vio
