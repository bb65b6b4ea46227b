#pragma once
// The local map behind a windowed policy (swf, msckf): keyframes and their
// landmarks stay live variables of the one cost after they leave the recent
// window, so a returning camera re-uses them and every pose they touch is
// re-linearized at each solve (as ORB-SLAM3's local mapping and OKVIS2's
// keyframe graph do).
//
// Frames: the newest `window_size` states are the recent window (the policy's
// own). A frame is a keyframe when less than `local_map_overlap` of its
// landmarks is seen by its reference keyframe, the keyframe (in the map or in
// the recent window) sharing most landmarks with it (IsKeyframe): a place
// already in the map makes no new keyframes by this rule. When a state leaves the recent
// window it joins the map if it is a keyframe and is dropped otherwise
// (Window::DropState: its observations go, its two IMU factors merge), so
// consecutive keyframes stay tied by IMU preintegration over the frames
// between them. A dropped frame's observations are not lost: each of a
// landmark the newest keyframe also sees goes, linearized, into a summary per
// landmark in the body frame of that keyframe (AnchoredPointSummary: the frame's pose relative to that keyframe
// held as estimated), one 3-row residual per keyframe and landmark
// (AnchoredPointFactor), so the map keeps what every frame saw at the cost of
// its keyframes; a state leaving the recent window also joins the map when the
// IMU factor from the last keyframe would otherwise span more than
// `local_map_max_link_s` (a camera circling a mapped place makes no keyframes
// by overlap, and one IMU factor over minutes would cost more every frame):
// the map's memory grows with the run's length, its cost per frame does not.
// Around a tracking loss: a frame that saw nothing does not join by the link
// rule, and no state joins without observations in the cost (a blind keyframe
// is only dead reckoning).
//
// The active set of a solve (SelectActiveSet): the recent window, the newest
// map keyframe (it carries the IMU factor into the window; held fixed instead
// when no recent frame sees it) and the keyframes sharing most landmarks with
// the recent window, K in all; their poses,
// speed/bias and landmarks are variables. Held fixed (conditioning): their
// IMU neighbours in the keyframe chain and the K keyframes sharing most
// landmarks with the active states. Every other keyframe, and every landmark
// no active state sees, is parked outside the cost (Window::RemoveState,
// DropLandmark) with its last estimate, and comes back when the active set
// needs it: the cost per frame is bounded by the window, 4K + 2 keyframes and
// their landmarks, whatever the run's length.
//
// Culling (IsCullable, CullKeyframe; local_map_culling.cc): a parked keyframe
// that joined by the link rule, is neither the first nor one of the newest K,
// and most of whose landmarks 4 other keyframes see leaves the map (its IMU
// factors merge, its summaries and anchored frames move to other keyframes), so
// a place circled for minutes does not pile up keyframes and the cost per
// frame stays flat.
//
// Data (LocalMapData) and functions over it; LocalMap applies them to a
// Window through the window's own operations.
#include <map>
#include <optional>
#include <set>
#include <vector>

#include "vio/estimator/anchored_point_factor.h"
#include "vio/estimator/estimator_options.h"
#include "vio/estimator/window.h"

namespace vio {

/// A keyframe that left the recent window, as last estimated in the window.
struct MapKeyframe {
  State state;
  std::map<LandmarkId, Eigen::Vector3d> observations;   ///< z = (u_L, u_R, v) [px]
  std::optional<ImuPreintegration> imu_from_previous;   ///< from the keyframe before it
  /// The observations of the frames dropped while it was the newest keyframe, of landmarks it
  /// observes, per landmark, summarized in its body frame (their poses relative to it held as
  /// they were estimated).
  std::map<LandmarkId, AnchoredPointSummary> anchored;
  /// Joined by the IMU link rule (local_map_max_link_s), not as a new view (IsKeyframe): only such
  /// keyframes are culled.
  bool by_link = false;
};

/// A landmark seen from a map keyframe.
struct MapLandmark {
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();  ///< last estimate [m]
  std::set<StateId> keyframes;                    ///< map keyframes observing it
};

/// A frame dropped from the recent window (not a keyframe): its state as it left and the
/// newest map keyframe's at that moment, so that its last estimate can move with the keyframe's.
struct DroppedFrame {
  State state;
  std::optional<State> anchor;  ///< none when no keyframe had joined the map yet
};

/// The local map's bookkeeping.
struct LocalMapData {
  std::map<StateId, MapKeyframe> keyframes;  ///< left the recent window, by id (= time) order
  std::map<LandmarkId, MapLandmark> landmarks;
  std::map<StateId, std::vector<LandmarkId>> recent;  ///< the recent window: each frame's landmarks
  std::set<StateId> recent_keyframes;                 ///< recent states that are keyframes
  std::set<StateId> live;                             ///< map keyframes in the window (active or fixed)
  std::vector<DroppedFrame> dropped;                  ///< in the order they left
};

/// A dropped frame's last estimate: its pose relative to its anchor keyframe as it left, composed
/// with the keyframe's `anchor_now` (ORB-SLAM3 writes its frames relative to their reference
/// keyframe so); speed turned with the keyframe, biases as they left.
State FollowAnchor(const DroppedFrame& frame, const State& anchor_now);

/// Which map keyframes a solve frees and which it holds fixed.
struct ActiveSet {
  std::set<StateId> active;
  std::set<StateId> fixed;
};

/// The keyframe rule: true when less than `overlap` of `frame_landmarks` is seen by the keyframe
/// (map or recent) sharing most of them; the first frame is one, an empty frame is not.
bool IsKeyframe(const std::vector<LandmarkId>& frame_landmarks, const LocalMapData& map, double overlap);

/// For each map keyframe seeing any of `landmarks`: how many of them it sees.
std::map<StateId, int> SharedLandmarks(const LocalMapData& map, const std::set<LandmarkId>& landmarks);

/// The active set for `keyframes` = K (see the file comment); empty when the map is.
ActiveSet SelectActiveSet(const LocalMapData& map, int keyframes);

/// True when at least `fraction` of the keyframe's landmarks is seen by 4 other map keyframes
/// (ORB-SLAM's redundancy, which asks 3); never when `fraction` <= 0.
bool IsRedundant(const LocalMapData& map, StateId id, double fraction);

/// True when `id` is a map keyframe that can leave the map: joined by the link rule, redundant,
/// parked, not the first and not one of the `kept_newest` newest (>= 1: an IMU factor into it and
/// out of it; the chain the recent window leans on keeps its short links).
bool IsCullable(const LocalMapData& map, StateId id, double fraction, int kept_newest);

/// The newest map keyframe that is not one of the `count` newest, if any.
std::optional<StateId> NewestBeyond(const LocalMapData& map, int count);

/// Removes a cullable keyframe from the map: its two IMU factors merge into the next keyframe's,
/// the frames anchored on it (and its own last estimate) follow the keyframe before it, its
/// summaries move to the parked keyframe nearest in time observing their landmark.
void CullKeyframe(LocalMapData& map, StateId id);

/// Counts over a run.
struct LocalMapCounts {
  int keyframes = 0;         ///< states that joined the map
  int dropped = 0;           ///< recent states dropped (not keyframes)
  int parked = 0;            ///< keyframes parked outside the cost
  int unparked = 0;          ///< keyframes brought back
  int culled = 0;            ///< keyframes culled from the map (redundant)
  int landmark_returns = 0;  ///< parked landmarks brought back because a new frame observes them
  int gated = 0;             ///< observations the map did not add again: predicted beyond the gate
  int most_states = 0;       ///< largest number of states in the cost [count]
};

class LocalMap {
 public:
  explicit LocalMap(const EstimatorOptions& options)
      : options_(options.local_map),
        window_size_(options.policy.window_size),
        gate_sigma_(options.model.max_whitened_residual),
        pixel_sigma_(options.model.pixel_sigma),
        max_link_ns_(SecondsToNanos(options.local_map.local_map_max_link_s)) {}
  bool enabled() const { return options_.local_map_keyframes > 0; }

  /// Before the frame's observations enter: records the frame (keyframe or
  /// not), applies the active set (including the frame's landmarks) and brings
  /// back the parked landmarks the frame observes. Returns the frame without
  /// its observations of returned landmarks predicted beyond the gate
  /// (max_whitened_residual, as the estimator gates the others); `parked`
  /// gets the keyframes parked.
  StereoFrame Prepare(const StereoFrame& frame, StateId state, Window& window, std::vector<StateId>* parked);
  /// The recent state the next Slide moves into the map (a keyframe, or a frame that saw
  /// landmarks and would otherwise leave a longer IMU link than local_map_max_link_s).
  std::optional<StateId> KeyframeLeaving(const Window& window) const;
  /// After the solve: the oldest state beyond the recent window joins the map
  /// (keyframe) or is dropped. Returns the dropped states.
  std::vector<StateId> Slide(Window& window);
  /// Every state that left the recent window, as the map last estimates it: each keyframe at its
  /// latest estimate (the window's while it is in it), each dropped frame with its anchor keyframe
  /// (FollowAnchor). Empty when the map is off.
  std::vector<State> LastStates(const Window& window) const;
  const LocalMapData& data() const { return data_; }
  const LocalMapCounts& counts() const { return counts_; }

 private:
  void Apply(const ActiveSet& set, const StereoFrame& frame, StateId state, Window& window,
             std::vector<StateId>* parked);
  void Park(StateId id, Window& window);
  void Unpark(StateId id, Window& window);
  void LinkChain(Window& window) const;
  void SyncLandmarks(const ActiveSet& set, const StereoFrame& frame, StateId state, Window& window);
  void AddKeyframeObservations(Window& window);
  void JoinMap(StateId id, Window& window);
  /// Culls `id` when it is cullable (IsCullable, the newest K kept).
  void MaybeCull(StateId id);
  /// The observations of `frame`, about to be dropped, into the summaries of `anchor` (live).
  void Summarize(StateId frame, StateId anchor, Window& window);
  /// Adds a live keyframe's summaries of landmarks in the cost, each within the gate.
  void AddAnchoredPoints(StateId keyframe, Window& window);
  /// A keyframe's latest estimate: the window's while it is live, else the map's.
  State LatestState(StateId keyframe, const Window& window) const;

  LocalMapOptions options_;
  int window_size_;
  double gate_sigma_;  ///< observations the map adds again must be predicted this well [sigma]
  double pixel_sigma_;  ///< stereo observation noise [px]
  Timestamp max_link_ns_;  ///< longest IMU factor between keyframes
  LocalMapData data_;
  LocalMapCounts counts_;
};

/// Logs the counts (at the end of a run) when the map is on.
void LogLocalMapCounts(const LocalMap& map);

}  // namespace vio
