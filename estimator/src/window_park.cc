// Window operations of the local map (local_map.h): a keyframe parked outside
// the cost and its bookkeeping read back.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>

#include <glog/logging.h>

#include "vio/estimator/window.h"

namespace vio {

void Window::RemoveState(StateId id) {
  State& s = state(id);
  for (auto it = priors_.begin(); it != priors_.end();) {
    const auto of_this = [&](const double* b) { return b == s.pose || b == s.speed_bias; };
    const auto mine = std::count_if(it->blocks.begin(), it->blocks.end(), of_this);
    const bool touches = mine > 0;
    CHECK(!touches || mine == static_cast<std::ptrdiff_t>(it->blocks.size()))
        << "state " << id.value << " shares a prior with other blocks";
    // The residual block goes with the state's parameter blocks below.
    it = touches ? priors_.erase(it) : std::next(it);
  }
  for (const auto& [landmark, z] : ObservationsOf(id)) DropObservation(id, landmark);
  for (const ObservationKey& key : AnchoredKeysOf(LeavingOf({id}, {}))) {
    landmarks_.at(key.second).anchored_to.erase(id);
    anchored_points_.erase(key);  // the residual block goes with the pose below
  }
  for (auto it = imu_edges_.begin(); it != imu_edges_.end();) {
    it = (it->second.from == id || it->first == id) ? imu_edges_.erase(it) : std::next(it);
  }
  problem_->RemoveParameterBlock(s.pose);
  problem_->RemoveParameterBlock(s.speed_bias);
  states_.erase(id);
}

std::vector<std::pair<LandmarkId, Eigen::Vector3d>> Window::ObservationsOf(StateId id) const {
  std::vector<std::pair<LandmarkId, Eigen::Vector3d>> out;
  for (auto it = observations_.lower_bound({id, LandmarkId(std::numeric_limits<std::int64_t>::min())});
       it != observations_.end() && it->first.first == id; ++it) {
    out.emplace_back(it->first.second, it->second.z_px);
  }
  return out;
}

const ImuPreintegration* Window::ImuFactorInto(StateId to, StateId* from) const {
  auto it = imu_edges_.find(to);
  if (it == imu_edges_.end()) return nullptr;
  if (from != nullptr) *from = it->second.from;
  return &it->second.preintegration;
}

}  // namespace vio
