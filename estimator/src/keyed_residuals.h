#pragma once
// Residual blocks of a Window in a fixed order, each with the keys of its
// parameter blocks: what the window knew when it added the residual (an IMU
// factor's two states, an observation's state and landmark, a prior's blocks),
// so that no block is ever looked up by its address.
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include <ceres/problem.h>

#include "vio/estimator/first_estimates.h"
#include "vio/estimator/types.h"

namespace vio {

/// The keys of an IMU factor's blocks, in its parameter order.
inline std::array<BlockKey, 4> ImuKeys(StateId from, StateId to) {
  return {BlockKey::Pose(from), BlockKey::SpeedBias(from), BlockKey::Pose(to), BlockKey::SpeedBias(to)};
}

/// The keys of a stereo observation's first blocks (its calibration blocks follow) and of an anchored point's.
inline std::array<BlockKey, 2> PointKeys(StateId state, LandmarkId landmark) {
  return {BlockKey::Pose(state), BlockKey::Landmark(landmark)};
}

struct KeyedResiduals {
  std::vector<ceres::ResidualBlockId> ids;
  /// Every residual's keys in its factor's parameter order, one residual after the other.
  std::vector<BlockKey> keys;
  /// Residual k's keys end at keys[ends[k]] (and start where residual k - 1's end).
  std::vector<std::size_t> ends;

  /// Appends a residual on the blocks [first, last), then `more`.
  void Add(ceres::ResidualBlockId id, const BlockKey* first, const BlockKey* last,
           const std::vector<BlockKey>& more = {}) {
    ids.push_back(id);
    keys.insert(keys.end(), first, last);
    keys.insert(keys.end(), more.begin(), more.end());
    ends.push_back(keys.size());
  }
  template <std::size_t N>
  void Add(ceres::ResidualBlockId id, const std::array<BlockKey, N>& of, const std::vector<BlockKey>& more = {}) {
    Add(id, of.data(), of.data() + N, more);
  }
  void Add(ceres::ResidualBlockId id, const std::vector<BlockKey>& of) { Add(id, of.data(), of.data() + of.size()); }
  std::size_t size() const { return ids.size(); }
  const BlockKey* begin(std::size_t k) const { return keys.data() + (k == 0 ? 0 : ends[k - 1]); }
  const BlockKey* end(std::size_t k) const { return keys.data() + ends[k]; }
};

/// A hash of a block's key, for lookups (never iterated).
struct BlockKeyHash {
  std::size_t operator()(const BlockKey& key) const {
    return std::hash<std::int64_t>()(key.id) * 8 + static_cast<std::size_t>(key.kind);
  }
};

}  // namespace vio
