#include "vio/estimator/local_map.h"

#include <algorithm>
#include <iterator>
#include <tuple>

#include <glog/logging.h>

#include "vio/estimator/stereo_factor.h"

namespace vio {
namespace {

// Keyframes by shared landmarks, most first; newer first among equals.
std::vector<StateId> MostShared(const std::map<StateId, int>& shared) {
  std::vector<std::pair<int, StateId>> ranked;
  for (const auto& [id, count] : shared) ranked.emplace_back(count, id);
  std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) {
    return std::make_tuple(-a.first, -a.second.value) < std::make_tuple(-b.first, -b.second.value);
  });
  std::vector<StateId> out;
  for (const auto& [count, id] : ranked) out.push_back(id);
  return out;
}

// The map keyframes before and after `id` in the chain (none at its ends).
std::vector<StateId> ChainNeighbours(const LocalMapData& map, StateId id) {
  std::vector<StateId> out;
  auto it = map.keyframes.find(id);
  if (it == map.keyframes.end()) return out;
  if (it != map.keyframes.begin()) out.push_back(std::prev(it)->first);
  if (std::next(it) != map.keyframes.end()) out.push_back(std::next(it)->first);
  return out;
}

std::set<LandmarkId> RecentLandmarks(const LocalMapData& map) {
  std::set<LandmarkId> out;
  for (const auto& [id, landmarks] : map.recent) out.insert(landmarks.begin(), landmarks.end());
  return out;
}

}  // namespace

bool IsKeyframe(const std::vector<LandmarkId>& frame_landmarks, const LocalMapData& map, double overlap) {
  if (map.keyframes.empty() && map.recent_keyframes.empty()) return true;
  if (frame_landmarks.empty()) return false;
  const std::set<LandmarkId> seen(frame_landmarks.begin(), frame_landmarks.end());
  int best = 0;
  for (const auto& [id, count] : SharedLandmarks(map, seen)) best = std::max(best, count);
  for (StateId id : map.recent_keyframes) {
    const std::vector<LandmarkId>& landmarks = map.recent.at(id);
    const int count = static_cast<int>(
        std::count_if(landmarks.begin(), landmarks.end(), [&](LandmarkId l) { return seen.count(l) > 0; }));
    best = std::max(best, count);
  }
  return best < overlap * static_cast<double>(seen.size());
}

std::map<StateId, int> SharedLandmarks(const LocalMapData& map, const std::set<LandmarkId>& landmarks) {
  std::map<StateId, int> shared;
  for (LandmarkId id : landmarks) {
    auto it = map.landmarks.find(id);
    if (it == map.landmarks.end()) continue;
    for (StateId keyframe : it->second.keyframes) ++shared[keyframe];
  }
  return shared;
}

ActiveSet SelectActiveSet(const LocalMapData& map, int keyframes) {
  ActiveSet set;
  if (map.keyframes.empty() || keyframes <= 0) return set;
  // The newest keyframe carries the IMU factor into the window: solved when a recent frame sees
  // it, else held fixed (a tracking loss then dead-reckons from its last estimate, as the
  // estimators without the map do from their prior, instead of freeing it on IMU factors alone).
  std::set<LandmarkId> landmarks = RecentLandmarks(map);
  const std::map<StateId, int> shared = SharedLandmarks(map, landmarks);
  const StateId newest = map.keyframes.rbegin()->first;
  (shared.count(newest) > 0 ? set.active : set.fixed).insert(newest);
  for (StateId id : MostShared(shared)) {
    if (static_cast<int>(set.active.size()) >= keyframes) break;
    set.active.insert(id);
  }
  for (StateId id : set.active) {
    for (StateId neighbour : ChainNeighbours(map, id)) {
      if (set.active.count(neighbour) == 0) set.fixed.insert(neighbour);
    }
    for (const auto& [landmark, z] : map.keyframes.at(id).observations) landmarks.insert(landmark);
  }
  int covisible = 0;
  for (StateId id : MostShared(SharedLandmarks(map, landmarks))) {
    if (covisible >= keyframes) break;
    if (set.active.count(id) > 0) continue;
    set.fixed.insert(id);
    ++covisible;
  }
  return set;
}

StereoFrame LocalMap::Prepare(const StereoFrame& frame, StateId state, Window& window, std::vector<StateId>* parked) {
  std::vector<LandmarkId> landmarks;
  std::set<LandmarkId> in_cost;  // gated by the estimator already
  for (const StereoObservation& obs : frame.observations) {
    landmarks.push_back(obs.landmark);
    if (window.HasLandmark(obs.landmark)) in_cost.insert(obs.landmark);
  }
  if (IsKeyframe(landmarks, data_, options_.local_map_overlap)) data_.recent_keyframes.insert(state);
  data_.recent[state] = landmarks;
  Apply(SelectActiveSet(data_, options_.local_map_keyframes), frame, state, window, parked);
  StereoFrame gated = frame;
  gated.observations.clear();
  for (const StereoObservation& obs : frame.observations) {
    const bool returned = window.HasLandmark(obs.landmark) && in_cost.count(obs.landmark) == 0;
    if (returned && !(window.WhitenedError(state, obs.landmark, obs.z_px) <= gate_sigma_)) {
      ++counts_.gated;
      continue;
    }
    gated.observations.push_back(obs);
  }
  return gated;
}

std::optional<StateId> LocalMap::KeyframeLeaving(const Window& window) const {
  if (static_cast<int>(data_.recent.size()) <= window_size_) return std::nullopt;
  const auto oldest = data_.recent.begin();
  if (data_.recent_keyframes.count(oldest->first) > 0) return oldest->first;
  // The long-link rule: a frame that saw nothing (tracking lost) never joins the map. It would be a
  // keyframe no measurement but the IMU places, later held fixed as a chain neighbour: after a
  // tracking loss the new window was then anchored to dead-reckoned poses and speeds.
  const bool long_link = !data_.keyframes.empty() && !oldest->second.empty() &&
                         window.state(std::next(oldest)->first).t_ns - data_.keyframes.rbegin()->second.state.t_ns >
                             max_link_ns_;
  if (long_link) return oldest->first;
  return std::nullopt;
}

std::vector<StateId> LocalMap::Slide(Window& window) {
  std::vector<StateId> dropped;
  if (static_cast<int>(data_.recent.size()) > window_size_) {
    const StateId oldest = data_.recent.begin()->first;
    // A state joins the map with landmarks in the cost or not at all: a blind keyframe (the MSCKF
    // triangulated none of its tracks, as after a tracking loss) would only be a dead-reckoned
    // pose and speed held fixed for the window to lean on.
    if (KeyframeLeaving(window) && !window.ObservationsOf(oldest).empty()) {
      JoinMap(oldest, window);
      // The keyframe the new one moves out of the newest K, if parked (else when it is parked).
      if (const std::optional<StateId> id = NewestBeyond(data_, options_.local_map_keyframes)) MaybeCull(*id);
    } else {
      // The newest keyframe, always live, is the dropped frame's anchor.
      DroppedFrame frame{window.state(oldest), std::nullopt};
      if (!data_.keyframes.empty()) {
        const StateId anchor = data_.keyframes.rbegin()->first;
        frame.anchor = window.state(anchor);
        Summarize(oldest, anchor, window);
      }
      data_.dropped.push_back(frame);
      window.DropState(oldest);
      dropped.push_back(oldest);
      ++counts_.dropped;
    }
    data_.recent_keyframes.erase(oldest);
    data_.recent.erase(oldest);
  }
  counts_.most_states = std::max(counts_.most_states, static_cast<int>(window.states().size()));
  return dropped;
}

State LocalMap::LatestState(StateId keyframe, const Window& window) const {
  return data_.live.count(keyframe) > 0 ? window.state(keyframe) : data_.keyframes.at(keyframe).state;
}

std::vector<State> LocalMap::LastStates(const Window& window) const {
  std::vector<State> out;
  for (const DroppedFrame& frame : data_.dropped) {
    out.push_back(frame.anchor ? FollowAnchor(frame, LatestState(frame.anchor->id, window)) : frame.state);
  }
  for (const auto& [id, keyframe] : data_.keyframes) out.push_back(LatestState(id, window));
  return out;
}

State FollowAnchor(const DroppedFrame& frame, const State& anchor_now) {
  const State& then = *frame.anchor;
  const Eigen::Quaterniond q_now_then = anchor_now.q_w_b() * then.q_w_b().conjugate();  // world at the drop -> now
  State out = frame.state;
  out.SetPose(anchor_now.p_w_b() + q_now_then * (frame.state.p_w_b() - then.p_w_b()),
              (q_now_then * frame.state.q_w_b()).normalized());
  out.SetSpeedBias(q_now_then * frame.state.v_w_b(), frame.state.gyro_bias(), frame.state.accel_bias());
  return out;
}

void LocalMap::Summarize(StateId frame, StateId anchor, Window& window) {
  MapKeyframe& keyframe = data_.keyframes.at(anchor);
  const State& a = window.state(anchor);
  const Eigen::Matrix3d R_w_a = a.q_w_b().toRotationMatrix();
  const State& f = window.state(frame);
  for (const auto& [landmark, z] : window.ObservationsOf(frame)) {
    // Only landmarks the keyframe sees itself: its summaries then number at most its observations
    // (all of the frame's landmarks made the residuals in the cost grow faster with the map's
    // density: 30 against 17 ms per frame after 10 minutes of circling one room; docs/local-map.md).
    if (keyframe.observations.count(landmark) == 0) continue;
    if (!(window.WhitenedError(frame, landmark, z) <= gate_sigma_)) continue;
    const Landmark& l = window.landmark(landmark);
    const double* parameters[2] = {f.pose, l.p_w};
    Eigen::Vector3d e0;
    Eigen::Matrix<double, 3, 6, Eigen::RowMajor> J_pose;
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> J_w;
    double* jacobians[2] = {J_pose.data(), J_w.data()};
    if (!StereoFactor::EvaluateAt(window.stereo(), z, 1.0 / pixel_sigma_, parameters, e0.data(), jacobians,
                                  /*on_tangents=*/true)) {
      continue;
    }
    AnchoredPointSummary& summary = keyframe.anchored[landmark];
    summary.Add(R_w_a.transpose() * (l.position() - a.p_w_b()), e0, J_w * R_w_a);
    data_.landmarks[landmark].p_w = l.position();
    if (summary.Usable()) window.SetAnchoredPoint(anchor, landmark, summary.mean(), summary.SqrtInformation());
  }
}

void LocalMap::AddAnchoredPoints(StateId id, Window& window) {
  for (const auto& [landmark, summary] : data_.keyframes.at(id).anchored) {
    if (!window.HasLandmark(landmark) || window.landmark(landmark).anchored_to.count(id) > 0 || !summary.Usable()) {
      continue;
    }
    const State& s = window.state(id);
    const Eigen::Vector3d p_b = s.q_w_b().conjugate() * (window.landmark(landmark).position() - s.p_w_b());
    const Eigen::Matrix3d L = summary.SqrtInformation();
    const Eigen::Vector3d mean = summary.mean();
    if (!((L * (p_b - mean)).norm() <= gate_sigma_)) {
      ++counts_.gated;
      continue;
    }
    window.SetAnchoredPoint(id, landmark, mean, L);
  }
}

void LocalMap::JoinMap(StateId id, Window& window) {
  MapKeyframe keyframe;
  keyframe.state = window.state(id);
  for (const auto& [landmark, z] : window.ObservationsOf(id)) {
    keyframe.observations[landmark] = z;
    MapLandmark& l = data_.landmarks[landmark];
    l.keyframes.insert(id);
    l.p_w = window.landmark(landmark).position();
  }
  if (const ImuPreintegration* imu = window.ImuFactorInto(id, nullptr)) keyframe.imu_from_previous = *imu;
  keyframe.by_link = data_.recent_keyframes.count(id) == 0;
  data_.keyframes[id] = std::move(keyframe);
  data_.live.insert(id);
  ++counts_.keyframes;
}

void LocalMap::Apply(const ActiveSet& set, const StereoFrame& frame, StateId state, Window& window,
                     std::vector<StateId>* parked) {
  const auto wanted = [&](StateId id) { return set.active.count(id) > 0 || set.fixed.count(id) > 0; };
  std::vector<StateId> leaving;
  for (StateId id : data_.live) {
    if (!wanted(id)) leaving.push_back(id);
  }
  for (StateId id : leaving) {
    Park(id, window);
    MaybeCull(id);
  }
  for (const std::set<StateId>* group : {&set.active, &set.fixed}) {
    for (StateId id : *group) {
      if (data_.live.count(id) == 0) Unpark(id, window);
    }
  }
  // Active keyframes free their whole state, speed and biases included: a keyframe's velocity and
  // biases held at an early estimate (the accelerometer bias is not observable before the motion
  // starts) tie the window's bias to that value through the IMU factors' random walk, and the
  // tilt takes up the rest (measured: 0.65 deg of tilt for the whole run instead of 0.1).
  for (StateId id : data_.live) window.SetStateConstant(id, set.fixed.count(id) > 0);
  LinkChain(window);
  SyncLandmarks(set, frame, state, window);
  AddKeyframeObservations(window);
  parked->insert(parked->end(), leaving.begin(), leaving.end());
}

// The keyframe's estimate and the IMU factors into it and out of it (re-preintegrated in the
// window) go to the map; the state leaves the cost.
void LocalMap::Park(StateId id, Window& window) {
  MapKeyframe& keyframe = data_.keyframes.at(id);
  keyframe.state = window.state(id);
  if (const ImuPreintegration* imu = window.ImuFactorInto(id, nullptr)) keyframe.imu_from_previous = *imu;
  auto next = data_.keyframes.upper_bound(id);
  if (next != data_.keyframes.end() && data_.live.count(next->first) > 0) {
    if (const ImuPreintegration* imu = window.ImuFactorInto(next->first, nullptr)) next->second.imu_from_previous = *imu;
  }
  window.RemoveState(id);
  data_.live.erase(id);
  ++counts_.parked;
}

void LocalMap::Unpark(StateId id, Window& window) {
  const State& parked = data_.keyframes.at(id).state;
  State& s = window.AddState(id, parked.t_ns);
  std::copy(std::begin(parked.pose), std::end(parked.pose), std::begin(s.pose));
  std::copy(std::begin(parked.speed_bias), std::end(parked.speed_bias), std::begin(s.speed_bias));
  data_.live.insert(id);
  ++counts_.unparked;
}

// Consecutive keyframes both in the window are tied by their IMU factor.
void LocalMap::LinkChain(Window& window) const {
  for (StateId id : data_.live) {
    auto it = data_.keyframes.find(id);
    if (it == data_.keyframes.begin() || !it->second.imu_from_previous) continue;
    const StateId previous = std::prev(it)->first;
    if (data_.live.count(previous) == 0 || window.ImuFactorInto(id, nullptr) != nullptr) continue;
    window.AddImuFactor(previous, id, *it->second.imu_from_previous);
  }
}

// Landmarks in the cost: those the recent frames and the active keyframes see. The others
// (seen from fixed keyframes only, or from no state in the cost) are parked with their estimate;
// parked ones the cost needs again come back when a state in it observes them, the frame's
// own observation within the gate (else the frame sees a new landmark).
void LocalMap::SyncLandmarks(const ActiveSet& set, const StereoFrame& frame, StateId state, Window& window) {
  std::set<LandmarkId> needed = RecentLandmarks(data_);
  for (StateId id : set.active) {
    for (const auto& [landmark, z] : data_.keyframes.at(id).observations) needed.insert(landmark);
  }
  std::vector<LandmarkId> leaving;
  for (const auto& [id, landmark] : window.landmarks()) {
    if (needed.count(id) == 0 || (landmark.observed_from.empty() && landmark.anchored_to.empty())) {
      leaving.push_back(id);
    }
  }
  for (LandmarkId id : leaving) {
    auto it = data_.landmarks.find(id);
    if (it != data_.landmarks.end()) it->second.p_w = window.landmark(id).position();
    window.DropLandmark(id);
  }
  std::map<LandmarkId, Eigen::Vector3d> in_frame;
  for (const StereoObservation& obs : frame.observations) in_frame[obs.landmark] = obs.z_px;
  for (LandmarkId id : needed) {
    auto it = data_.landmarks.find(id);
    if (window.HasLandmark(id) || it == data_.landmarks.end()) continue;
    const bool seen_live = std::any_of(it->second.keyframes.begin(), it->second.keyframes.end(),
                                       [&](StateId k) { return data_.live.count(k) > 0; });
    auto z = in_frame.find(id);
    if (!seen_live && z == in_frame.end()) continue;
    window.AddLandmark(id, it->second.p_w);
    if (z == in_frame.end()) continue;
    if (window.WhitenedError(state, id, z->second) <= gate_sigma_) {
      ++counts_.landmark_returns;
    } else {
      // The frame disagrees with the map's estimate (after a tracking loss the window has drifted
      // from the map): the landmark stays parked and the frame's observation starts it anew, as
      // the policy does for any landmark; the map's views are tied to it again, each within the
      // gate, once it is back in the cost from the new frames.
      window.DropLandmark(id);
      ++counts_.gated;
    }
  }
}

// The live keyframes' observations of landmarks in the cost, each within the gate.
void LocalMap::AddKeyframeObservations(Window& window) {
  for (StateId id : data_.live) {
    for (const auto& [landmark, z] : data_.keyframes.at(id).observations) {
      if (!window.HasLandmark(landmark) || window.landmark(landmark).observed_from.count(id) > 0) continue;
      if (!(window.WhitenedError(id, landmark, z) <= gate_sigma_)) {
        ++counts_.gated;
        continue;
      }
      window.AddObservation(id, landmark, z);
    }
    AddAnchoredPoints(id, window);
  }
}

void LogLocalMapCounts(const LocalMap& map) {
  if (!map.enabled()) return;
  const LocalMapCounts& c = map.counts();
  LOG(INFO) << "local map: " << c.keyframes << " keyframes, " << c.dropped << " frames dropped, " << c.parked
            << " keyframes parked, " << c.culled << " culled, " << c.unparked << " brought back, " << c.landmark_returns
            << " parked landmarks observed again, " << c.gated << " observations beyond the gate not added again; at most "
            << c.most_states << " states in the cost";
}

}  // namespace vio
