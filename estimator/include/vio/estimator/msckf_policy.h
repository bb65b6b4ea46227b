#pragma once
// The MSCKF restated as optimization (paper Algorithm 4, Remark 4.3.2), and
// the fixed-lag smoother that shares its marginalization (paper §4.4).
//
// States are linked by IMU factors as in every policy. Landmarks are NOT
// parameters while their tracks grow: the policy keeps their observations.
// A track is used when it ends (not seen in the newest frame): the landmark
// is triangulated from all its observations in the window (multi-view,
// refined by Gauss-Newton, rejected when ill-conditioned, behind a camera or
// inconsistent), added with them, the window takes `msckf_gn_steps`
// Gauss-Newton steps (one: the MSCKF update; to convergence: fixed_lag), and
// the landmark is marginalized at once. When the window exceeds n states, the
// evenly spaced states x_i, i mod 3 == 2 (1-based, oldest first), are
// marginalized in the same step, after their observations were used: a track
// seen from every leaving state gives those views (Algorithm 4, line 12) and
// goes on without them (`leaving_views`), or one seen from at least two of
// them does (`shared_views`, the default: Algorithm 4 loses a young track's
// views from the leaving states it was seen from), or, with `whole_track`,
// any track seen from a leaving state is used whole and restarts. Older poses
// thin out, so the window reaches arbitrarily far into the past.
//
// The triangulation's reprojection gate is msckf_max_reprojection, raised to
// msckf_gate_median_factor times the median error of the frame's tracks: after
// dead reckoning (a tracking loss, dropped frames) every track disagrees with
// the drifted poses, and a fixed gate rejected them all for seconds.
//
// With persistent_landmarks > 0 (persistent_landmarks.h), a track about to
// be used that was observed at least persistent_min_track times may be kept:
// its landmark is triangulated from the whole track, added, and stays a
// parameter (OpenVINS' "SLAM features"); its later observations are added to
// the window directly, its views from leaving states go into the prior.
//
// With local_map_keyframes > 0 (local_map.h) nothing is marginalized: used
// landmarks stay in the cost, the state leaving the recent window joins the
// local map (a keyframe: the tracks seen from it are used whole first) or is
// dropped, and map landmarks a frame observes again take its observation
// directly, as kept landmarks do.
#include <map>
#include <optional>
#include <vector>

#include "vio/estimator/local_map.h"
#include "vio/estimator/persistent_landmarks.h"
#include "vio/estimator/policy.h"
#include "vio/estimator/triangulation.h"

namespace vio {

/// What the MSCKF did with tracks (cumulative).
struct MsckfCounts {
  int used = 0;             ///< tracks triangulated and marginalized
  int too_short = 0;        ///< ended with fewer observations than required
  int rejected = 0;         ///< triangulation rejected
  int used_views = 0;       ///< observations in used tracks
  int rejected_views = 0;   ///< observations in rejected tracks
  int forgotten_views = 0;  ///< observations lost with their leaving state, never used
};

class MsckfPolicy final : public Policy {
 public:
  /// `gn_steps`: Gauss-Newton steps per update (1 = MSCKF); none: to
  /// convergence (fixed_lag).
  MsckfPolicy(const EstimatorOptions& options, std::optional<int> gn_steps);
  PolicyTiming Update(const StereoFrame& frame, StateId new_state, Window& window) override;
  /// Logs the long-lived landmarks' counts; the trajectory is the filter's.
  bool Finish(Window& /*window*/) override;
  const MsckfCounts& counts() const { return counts_; }
  const PersistentLandmarks& persistent() const { return persistent_; }
  const LocalMap& local_map() const { return local_map_; }
  std::vector<State> StatesBehindWindow(const Window& window) const override { return local_map_.LastStates(window); }

 private:
  using Observation = std::pair<StateId, Eigen::Vector3d>;
  /// Observations of one landmark to triangulate, add and marginalize now.
  struct TrackUpdate {
    LandmarkId id;
    std::vector<Observation> observations;
  };

  std::vector<StateId> LeavingStates(const Window& window) const;
  std::vector<TrackUpdate> PromoteTracks(const StereoFrame& frame, const std::vector<StateId>& leaving,
                                         const Window& window, std::vector<LandmarkId>& retired);
  std::vector<TrackUpdate> MatureTracks(const StereoFrame& frame, const std::vector<StateId>& leaving);
  std::optional<TrackUpdate> LeavingViews(std::vector<Observation>& track, LandmarkId id,
                                          const std::vector<StateId>& leaving) const;
  std::vector<LandmarkId> AddTriangulated(const std::vector<TrackUpdate>& updates, Window& window);
  double ReprojectionGate(const std::vector<TriangulationResult>& results) const;
  void ForgetObservationsOf(const std::vector<StateId>& leaving);
  void LeaveWindow(const std::vector<StateId>& leaving, const std::vector<LandmarkId>& added,
                   const std::vector<LandmarkId>& retired, Window& window);
  std::vector<TrackUpdate> TracksSeenFrom(StateId keyframe);
  void AttachTracksOfLandmarksInTheCost(Window& window);
  std::optional<int> GaussNewtonSteps(const StereoFrame& frame);

  EstimatorOptions options_;
  std::optional<int> gn_steps_;
  std::map<LandmarkId, std::vector<Observation>> tracks_;  ///< unused observations, oldest first
  MsckfCounts counts_;
  PersistentLandmarks persistent_;  ///< long-lived landmarks (off unless persistent_landmarks > 0)
  LocalMap local_map_;              ///< off unless local_map_keyframes > 0
  int frames_without_observations_ = 0;  ///< the current run of empty frames (tracking loss)
  int reanchor_frames_ = 0;              ///< frames left solving to convergence after a long loss
};

}  // namespace vio
