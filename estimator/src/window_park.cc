// Window operations of the local map (local_map.h): a keyframe parked outside
// the cost and its bookkeeping read back, and the summaries of dropped frames'
// observations anchored on keyframes.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>

#include <glog/logging.h>

#include "vio/estimator/window.h"

#include "keyed_residuals.h"
#include "vio/estimator/anchored_point_factor.h"

namespace vio {

void Window::SetAnchoredPoint(StateId anchor, LandmarkId landmark_id, const Eigen::Vector3d& p_b_hat,
                              const Eigen::Matrix3d& sqrt_information) {
  State& s = state(anchor);
  auto it = landmarks_.find(landmark_id);
  CHECK(it != landmarks_.end()) << "anchored point of unknown landmark " << landmark_id.value;
  const ObservationKey key{anchor, landmark_id};
  auto existing = anchored_points_.find(key);
  if (existing != anchored_points_.end()) problem_->RemoveResidualBlock(existing->second);
  const auto keys = PointKeys(anchor, landmark_id);
  anchored_points_[key] =
      problem_->AddResidualBlock(WithFirstEstimates(Wrap(new AnchoredPointFactor(p_b_hat, sqrt_information)),
                                                    {keys.begin(), keys.end()}),
                                 nullptr, s.pose, it->second.p_w);
  it->second.anchored_to.insert(anchor);
}

void Window::RemoveState(StateId id) {
  State& s = state(id);
  for (auto it = priors_.begin(); it != priors_.end();) {
    const auto mine = std::count_if(it->keys.begin(), it->keys.end(), [id](const BlockKey& k) { return k.IsOf(id); });
    const auto calibration =
        std::count_if(it->keys.begin(), it->keys.end(), [](const BlockKey& k) { return k.IsCalibration(); });
    const bool touches = mine > 0;
    CHECK(!touches || mine + calibration == static_cast<std::ptrdiff_t>(it->keys.size()))
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
  RemoveStateBookkeeping(id);
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
