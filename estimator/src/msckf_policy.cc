#include "vio/estimator/msckf_policy.h"

#include <algorithm>
#include <chrono>
#include <set>

#include <glog/logging.h>

#include "vio/estimator/triangulation.h"

namespace vio {
namespace {

Eigen::Isometry3d BodyPose(const State& s) {
  Eigen::Isometry3d T_w_b = Eigen::Isometry3d::Identity();
  T_w_b.linear() = s.q_w_b().toRotationMatrix();
  T_w_b.translation() = s.p_w_b();
  return T_w_b;
}

// The loosest reprojection gate the MSCKF applies [sigma].
double MostReprojectionError(const EstimatorOptions& options) {
  return std::max(options.msckf.msckf_max_reprojection, options.model.max_whitened_residual);
}

bool IsLeaving(StateId state, const std::vector<StateId>& leaving) {
  return std::find(leaving.begin(), leaving.end(), state) != leaving.end();
}

}  // namespace

MsckfPolicy::MsckfPolicy(const EstimatorOptions& options, std::optional<int> gn_steps)
    : options_(options), gn_steps_(gn_steps), persistent_(options.persistent), local_map_(options) {
  CHECK(!gn_steps_ || *gn_steps_ >= 1);
  CHECK_GE(options_.policy.window_size, 2) << "the MSCKF needs a window of at least 2 states";
}

PolicyTiming MsckfPolicy::Update(const StereoFrame& given, StateId new_state, Window& window) {
  PolicyTiming timing;
  auto start = std::chrono::steady_clock::now();
  StereoFrame gated;  // the local map's: the frame without re-additions beyond the gate
  if (local_map_.enabled()) {
    std::vector<StateId> parked;
    gated = local_map_.Prepare(given, new_state, window, &parked);
    ForgetObservationsOf(parked);
    AttachTracksOfLandmarksInTheCost(window);
  }
  const StereoFrame& frame = local_map_.enabled() ? gated : given;
  for (const StereoObservation& obs : frame.observations) {
    if (window.HasLandmark(obs.landmark)) {  // a kept landmark: the observation re-attaches to it
      window.AddObservation(new_state, obs.landmark, obs.z_px);
    } else {
      tracks_[obs.landmark].emplace_back(new_state, obs.z_px);
    }
  }
  persistent_.Observe(frame);
  const std::vector<StateId> leaving = local_map_.enabled() ? std::vector<StateId>{} : LeavingStates(window);
  std::vector<LandmarkId> retired;
  std::vector<TrackUpdate> updates = PromoteTracks(frame, leaving, window, retired);
  for (TrackUpdate& update : MatureTracks(frame, leaving)) updates.push_back(std::move(update));
  if (const std::optional<StateId> keyframe = local_map_.KeyframeLeaving(window)) {
    for (TrackUpdate& update : TracksSeenFrom(*keyframe)) updates.push_back(std::move(update));
  }
  const std::vector<LandmarkId> added = AddTriangulated(updates, window);
  window.RefreshImuFactors(options_.model.reintegrate_bias_threshold);
  timing.build_ms = MillisecondsSince(start);

  start = std::chrono::steady_clock::now();
  const std::optional<int> steps = GaussNewtonSteps(frame);
  const SolveReport report = steps ? window.TakeSteps(*steps, options_.solver) : window.Solve(options_.solver);
  timing.solver_iterations = report.iterations;
  timing.solve_ms = MillisecondsSince(start);
  VLOG(1) << "msckf t=" << frame.t_ns << ": " << added.size() << " landmarks, " << leaving.size()
          << " states leaving, " << updates.size() << " updates (" << counts_.rejected << " rejected so far), cost "
          << report.initial_cost << " -> " << report.final_cost;

  start = std::chrono::steady_clock::now();
  LeaveWindow(leaving, added, retired, window);
  timing.marginalize_ms = MillisecondsSince(start);
  return timing;
}

// The MSCKF marginalizes the leaving states and the landmarks it used (kept
// ones stay, retired ones go). With the local map nothing is marginalized:
// the used landmarks join the cost, the oldest recent state joins the map or
// is dropped.
void MsckfPolicy::LeaveWindow(const std::vector<StateId>& leaving, const std::vector<LandmarkId>& added,
                              const std::vector<LandmarkId>& retired, Window& window) {
  if (local_map_.enabled()) {
    ForgetObservationsOf(local_map_.Slide(window));
    return;
  }
  // The solve may have dropped some of them (Window::Solve drops the observations that fail at a
  // rejected step's end point, and a landmark they leave unobserved): only those still there go.
  persistent_.ForgetAbsent(window);
  std::vector<LandmarkId> marginalized;
  for (LandmarkId id : added) {
    if (!persistent_.IsKept(id) && window.HasLandmark(id)) marginalized.push_back(id);
  }
  for (LandmarkId id : retired) {
    if (window.HasLandmark(id)) marginalized.push_back(id);
  }
  window.Marginalize(leaving, marginalized);
  ForgetObservationsOf(leaving);
}

// Local map: a pending track whose landmark the map brought back into the cost gives it its
// views (those within the reprojection gate) and ends.
void MsckfPolicy::AttachTracksOfLandmarksInTheCost(Window& window) {
  for (auto it = tracks_.begin(); it != tracks_.end();) {
    if (!window.HasLandmark(it->first)) {
      ++it;
      continue;
    }
    for (const auto& [state, z] : it->second) {
      if (window.WhitenedError(state, it->first, z) <= options_.model.max_whitened_residual) {
        window.AddObservation(state, it->first, z);
      }
    }
    it = tracks_.erase(it);
  }
}

// Local map: the tracks seen from a keyframe about to leave the recent window
// are used whole (they restart): its landmarks join the map with it.
std::vector<MsckfPolicy::TrackUpdate> MsckfPolicy::TracksSeenFrom(StateId keyframe) {
  std::vector<TrackUpdate> updates;
  for (auto it = tracks_.begin(); it != tracks_.end();) {
    const std::vector<Observation>& observations = it->second;
    const bool seen = std::any_of(observations.begin(), observations.end(),
                                  [&](const Observation& o) { return o.first == keyframe; });
    if (!seen || static_cast<int>(observations.size()) < options_.msckf.msckf_min_track_length) {
      ++it;
      continue;
    }
    updates.push_back({it->first, std::move(it->second)});
    it = tracks_.erase(it);
  }
  return updates;
}

bool MsckfPolicy::Finish(Window& /*window*/) {
  LOG(INFO) << "msckf tracks: " << counts_.used << " used (" << counts_.used_views << " views), " << counts_.rejected
            << " rejected by triangulation (" << counts_.rejected_views << " views), " << counts_.too_short
            << " too short; " << counts_.forgotten_views << " views left with their state unused";
  LogPersistentCounts(persistent_);
  LogLocalMapCounts(local_map_);
  return false;
}

// Re-anchoring after a tracking loss longer than the window: every state in
// it is then IMU dead reckoning, and the first updates of the new tracks are
// linearized far from their solution; for one window of frames they take
// Gauss-Newton steps to convergence, as the fixed-lag smoother does, instead
// of gn_steps.
std::optional<int> MsckfPolicy::GaussNewtonSteps(const StereoFrame& frame) {
  if (frame.observations.empty()) {
    ++frames_without_observations_;
  } else {
    if (frames_without_observations_ > options_.policy.window_size) reanchor_frames_ = options_.policy.window_size;
    frames_without_observations_ = 0;
  }
  if (reanchor_frames_ == 0 || frame.observations.empty()) return gn_steps_;
  --reanchor_frames_;
  return std::nullopt;
}

// x_i with i mod 3 == 2 (1-based, oldest first) once the window is over
// size; the newest state (the current IMU state) never leaves.
std::vector<StateId> MsckfPolicy::LeavingStates(const Window& window) const {
  std::vector<StateId> leaving;
  const int n = static_cast<int>(window.states().size());
  if (n <= options_.policy.window_size) return leaving;
  int i = 1;
  for (const auto& [id, state] : window.states()) {
    if (i < n && i % 3 == 2) leaving.push_back(id);
    ++i;
  }
  return leaving;
}

// Long-lived landmarks: tracks about to be used (ended, or seen from a
// leaving state) compete for the budget; a promoted track is used whole, and
// its landmark stays (not marginalized with the update). `retired`: kept
// landmarks to marginalize now.
std::vector<MsckfPolicy::TrackUpdate> MsckfPolicy::PromoteTracks(const StereoFrame& frame,
                                                                 const std::vector<StateId>& leaving,
                                                                 const Window& window,
                                                                 std::vector<LandmarkId>& retired) {
  std::vector<TrackUpdate> updates;
  if (!persistent_.enabled()) return updates;
  persistent_.ForgetAbsent(window);
  std::set<LandmarkId> seen_now;
  for (const StereoObservation& obs : frame.observations) seen_now.insert(obs.landmark);
  std::vector<PromotionCandidate> candidates;
  for (const auto& [id, observations] : tracks_) {
    const bool ended = seen_now.count(id) == 0;
    const bool loses_state = std::any_of(observations.begin(), observations.end(),
                                         [&](const Observation& o) { return IsLeaving(o.first, leaving); });
    if (static_cast<int>(observations.size()) < options_.msckf.msckf_min_track_length || !(ended || loses_state)) {
      continue;
    }
    candidates.push_back({id, static_cast<int>(observations.size()), window.state(observations.back().first).t_ns});
  }
  PersistentDecision decision = persistent_.Decide(frame.t_ns, candidates);
  for (LandmarkId id : decision.promoted) {
    auto it = tracks_.find(id);
    updates.push_back({id, std::move(it->second)});
    tracks_.erase(it);
  }
  retired = std::move(decision.retired);
  return updates;
}

// Tracks not seen in the newest frame give all their observations. Tracks
// seen from a leaving state give all of them too and restart (whole_track),
// or only their views from the leaving states, and go on: when seen from
// every leaving state (leaving_views) or from at least two (shared_views).
std::vector<MsckfPolicy::TrackUpdate> MsckfPolicy::MatureTracks(const StereoFrame& frame,
                                                                const std::vector<StateId>& leaving) {
  std::set<LandmarkId> seen_now;
  for (const StereoObservation& obs : frame.observations) seen_now.insert(obs.landmark);
  const bool whole_track = options_.msckf.msckf_leaving_update == "whole_track";
  std::vector<TrackUpdate> updates;
  for (auto it = tracks_.begin(); it != tracks_.end();) {
    std::vector<Observation>& observations = it->second;
    const bool ended = seen_now.count(it->first) == 0;
    const bool long_enough = static_cast<int>(observations.size()) >= options_.msckf.msckf_min_track_length;
    const bool loses_state = std::any_of(observations.begin(), observations.end(),
                                         [&](const Observation& o) { return IsLeaving(o.first, leaving); });
    if (ended && !long_enough) {
      ++counts_.too_short;
      it = tracks_.erase(it);
      continue;
    }
    if (long_enough && (ended || (whole_track && loses_state))) {
      updates.push_back({it->first, std::move(observations)});
      it = tracks_.erase(it);
      continue;
    }
    if (loses_state && !whole_track) {
      if (std::optional<TrackUpdate> update = LeavingViews(observations, it->first, leaving)) {
        updates.push_back(std::move(*update));
      }
    }
    ++it;
  }
  return updates;
}

// Paper Algorithm 4, line 12: the track's views from the leaving states when
// it was seen from each of them (leaving_views) or from at least two of them
// (shared_views: a young track is rarely seen from the oldest leaving state,
// and its views from the others would be lost); removed from the track.
std::optional<MsckfPolicy::TrackUpdate> MsckfPolicy::LeavingViews(std::vector<Observation>& track, LandmarkId id,
                                                                  const std::vector<StateId>& leaving) const {
  TrackUpdate update{id, {}};
  for (const Observation& o : track) {
    if (IsLeaving(o.first, leaving)) update.observations.push_back(o);
  }
  const bool every_leaving_state = options_.msckf.msckf_leaving_update == "leaving_views";
  const std::size_t needed = every_leaving_state ? leaving.size() : std::min<std::size_t>(2, leaving.size());
  if (update.observations.size() < needed ||
      static_cast<int>(update.observations.size()) < options_.msckf.msckf_min_track_length) {
    return std::nullopt;
  }
  track.erase(std::remove_if(track.begin(), track.end(),
                             [&](const Observation& o) { return IsLeaving(o.first, leaving); }),
              track.end());
  return update;
}

// Triangulates each update's observations and adds the landmark with them;
// rejected ones are counted and their observations dropped. The
// reprojection gate is ReprojectionGate's, over this frame's tracks.
std::vector<LandmarkId> MsckfPolicy::AddTriangulated(const std::vector<TrackUpdate>& updates, Window& window) {
  TriangulationOptions triangulation;
  triangulation.pixel_sigma = options_.model.pixel_sigma;
  triangulation.max_reprojection_sigma = MostReprojectionError(options_);
  triangulation.max_position_sigma_m = options_.msckf.msckf_max_landmark_sigma;
  std::vector<TriangulationResult> results;
  results.reserve(updates.size());
  std::vector<StereoView> views;
  for (const TrackUpdate& update : updates) {
    views.clear();
    views.reserve(update.observations.size());
    for (const auto& [state, z] : update.observations) views.push_back({BodyPose(window.state(state)), z});
    results.push_back(TriangulateMultiView(views, window.estimated_stereo(), triangulation));
  }
  const double gate = ReprojectionGate(results);
  std::vector<LandmarkId> added;
  for (std::size_t k = 0; k < updates.size(); ++k) {
    const TrackUpdate& update = updates[k];
    if (!results[k].p_w || results[k].max_error_sigma > gate) {
      ++counts_.rejected;
      counts_.rejected_views += static_cast<int>(update.observations.size());
      persistent_.Release(update.id);
      continue;
    }
    window.AddLandmark(update.id, *results[k].p_w);
    counts_.used_views += static_cast<int>(update.observations.size());
    for (const auto& [state, z] : update.observations) window.AddObservation(state, update.id, z);
    added.push_back(update.id);
    ++counts_.used;
  }
  return added;
}

// The largest whitened reprojection error a track may have: at least
// msckf_max_reprojection, and msckf_gate_median_factor times the median of
// this frame's tracks (at least kMinTracksForMedian of them) when that is
// larger: poses that drifted (IMU dead reckoning through a tracking loss or a
// burst of dropped frames) raise every track's error, a wrong association
// only its own. The raised gate stays within max_whitened_residual, the
// window's own gate on observations.
double MsckfPolicy::ReprojectionGate(const std::vector<TriangulationResult>& results) const {
  constexpr std::size_t kMinTracksForMedian = 5;
  const double absolute = options_.msckf.msckf_max_reprojection;
  std::vector<double> errors;
  for (const TriangulationResult& r : results) {
    if (r.p_w) errors.push_back(r.max_error_sigma);
  }
  if (options_.msckf.msckf_gate_median_factor <= 0.0 || errors.size() < kMinTracksForMedian) return absolute;
  std::nth_element(errors.begin(), errors.begin() + static_cast<std::ptrdiff_t>(errors.size() / 2), errors.end());
  const double relative = options_.msckf.msckf_gate_median_factor * errors[errors.size() / 2];
  return std::min(std::max(absolute, relative), MostReprojectionError(options_));
}

// Observations from marginalized states that no used track carried are lost
// with them (counted): views of tracks too short to use, or not seen from
// enough leaving states (leaving_views: all of them; shared_views: two).
void MsckfPolicy::ForgetObservationsOf(const std::vector<StateId>& leaving) {
  for (auto it = tracks_.begin(); it != tracks_.end();) {
    auto& observations = it->second;
    const std::size_t before = observations.size();
    observations.erase(std::remove_if(observations.begin(), observations.end(),
                                      [&](const Observation& o) { return IsLeaving(o.first, leaving); }),
                       observations.end());
    counts_.forgotten_views += static_cast<int>(before - observations.size());
    it = observations.empty() ? tracks_.erase(it) : std::next(it);
  }
}

}  // namespace vio
