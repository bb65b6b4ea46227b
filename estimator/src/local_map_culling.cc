// Keyframe culling of the local map (local_map.h), as ORB-SLAM's local mapping
// culls: a keyframe most of whose landmarks at least four other keyframes see (ORB-SLAM: three)
// adds little but residuals to every solve it is live in. When it leaves the
// cost it leaves the map: its two IMU factors merge into one (the chain stays
// whole, as Window::DropState merges a dropped frame's), the frames anchored
// on it follow the keyframe before it, and its own last estimate joins them.
#include <cstdlib>
#include <iterator>
#include <optional>

#include <glog/logging.h>

#include "vio/estimator/local_map.h"

namespace vio {

bool IsRedundant(const LocalMapData& map, StateId id, double fraction) {
  constexpr int kOtherObservers = 4;  // ORB-SLAM: 3 (docs/local-map.md)
  if (fraction <= 0) return false;
  const MapKeyframe& keyframe = map.keyframes.at(id);
  if (keyframe.observations.empty()) return false;
  int covered = 0;
  for (const auto& [landmark, z] : keyframe.observations) {
    auto it = map.landmarks.find(landmark);
    const int others = it == map.landmarks.end() ? 0 : static_cast<int>(it->second.keyframes.size()) - 1;
    covered += others >= kOtherObservers;
  }
  return covered >= fraction * static_cast<double>(keyframe.observations.size());
}

namespace {

// The parked keyframe nearest in time to `id` that observes `landmark`, if any.
std::optional<StateId> NearestParkedObserver(const LocalMapData& map, StateId id, LandmarkId landmark) {
  std::optional<StateId> best;
  for (StateId k : map.landmarks.at(landmark).keyframes) {
    if (k == id || map.live.count(k) > 0) continue;
    if (!best || std::abs(k.value - id.value) < std::abs(best->value - id.value)) best = k;
  }
  return best;
}

// The culled keyframe's summaries move to the parked keyframe nearest in time that observes each
// landmark, with the two keyframes' poses relative to each other held as estimated (a live one
// would need its residual in the window renewed); a landmark no parked keyframe sees loses its.
void MoveSummaries(LocalMapData& map, StateId id) {
  const MapKeyframe& from = map.keyframes.at(id);
  for (const auto& [landmark, summary] : from.anchored) {
    const std::optional<StateId> to = NearestParkedObserver(map, id, landmark);
    if (!to) continue;
    MapKeyframe& target = map.keyframes.at(*to);
    const Eigen::Matrix3d R_w_t = target.state.q_w_b().toRotationMatrix();
    target.anchored[landmark].Absorb(summary, R_w_t.transpose() * from.state.q_w_b().toRotationMatrix(),
                                     R_w_t.transpose() * (from.state.p_w_b() - target.state.p_w_b()));
  }
}

// Parked, between two keyframes and tied to both by IMU factors.
bool CanLeaveMap(const LocalMapData& map, StateId id) {
  auto it = map.keyframes.find(id);
  if (it == map.keyframes.end() || it == map.keyframes.begin() || std::next(it) == map.keyframes.end()) return false;
  return map.live.count(id) == 0 && it->second.imu_from_previous && std::next(it)->second.imu_from_previous;
}

}  // namespace

std::optional<StateId> NewestBeyond(const LocalMapData& map, int count) {
  auto it = map.keyframes.rbegin();
  for (int i = 0; i < count && it != map.keyframes.rend(); ++i) ++it;
  if (it == map.keyframes.rend()) return std::nullopt;
  return it->first;
}

bool IsCullable(const LocalMapData& map, StateId id, double fraction, int kept_newest) {
  const std::optional<StateId> newest_not_kept = NewestBeyond(map, kept_newest);
  const bool among_newest = !newest_not_kept || id.value > newest_not_kept->value;
  return CanLeaveMap(map, id) && !among_newest && map.keyframes.at(id).by_link &&
         IsRedundant(map, id, fraction);
}

void LocalMap::MaybeCull(StateId id) {
  if (!IsCullable(data_, id, options_.local_map_cull, options_.local_map_keyframes)) return;
  CullKeyframe(data_, id);
  ++counts_.culled;
}

void CullKeyframe(LocalMapData& map, StateId id) {
  CHECK(CanLeaveMap(map, id)) << "keyframe " << id.value << " cannot be culled";
  auto it = map.keyframes.find(id);
  MapKeyframe& previous = std::prev(it)->second;
  MapKeyframe& next = std::next(it)->second;
  ImuPreintegration merged = *it->second.imu_from_previous;
  merged.Append(*next.imu_from_previous);
  next.imu_from_previous = std::move(merged);
  // The frames anchored on it keep their pose relative to it as estimated now, and follow the
  // keyframe before it from here on; so does the keyframe itself.
  for (DroppedFrame& frame : map.dropped) {
    if (!frame.anchor || frame.anchor->id != id) continue;
    frame.state = FollowAnchor(frame, it->second.state);
    frame.anchor = previous.state;
  }
  map.dropped.push_back(DroppedFrame{it->second.state, previous.state});
  MoveSummaries(map, id);
  for (const auto& [landmark, z] : it->second.observations) map.landmarks.at(landmark).keyframes.erase(id);
  map.keyframes.erase(it);
}

}  // namespace vio
