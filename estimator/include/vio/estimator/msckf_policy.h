#pragma once
// The MSCKF restated as optimization (paper Algorithm 4, Remark 4.3.2), and
// the fixed-lag smoother that shares its marginalization (paper §4.4).
//
// States are linked by IMU factors as in every policy. Landmarks are NOT
// parameters while their tracks grow: the policy keeps their observations.
// A track is used when it ends (not seen in the newest frame) or when a
// state it was seen from is about to leave: the landmark is triangulated from
// all its observations in the window (multi-view, refined by Gauss-Newton,
// rejected when ill-conditioned, behind a camera or inconsistent), added with
// all its observations, the window takes `msckf_gn_steps` Gauss-Newton steps
// (one: the MSCKF update; to convergence: fixed_lag), and the landmark is
// marginalized at once. When the window exceeds n states, the evenly spaced
// states x_i, i mod 3 == 2 (1-based, oldest first), are marginalized in the
// same step, after their observations were used: older poses thin out, so
// the window reaches arbitrarily far into the past.
#include <map>
#include <vector>

#include "vio/estimator/policy.h"

namespace vio {

/// What the MSCKF did with tracks (cumulative).
struct MsckfCounts {
  int used = 0;             ///< tracks triangulated and marginalized
  int too_short = 0;        ///< ended with fewer observations than required
  int rejected = 0;         ///< triangulation rejected
};

class MsckfPolicy final : public Policy {
 public:
  /// `gn_steps`: Gauss-Newton steps per update (1 = MSCKF).
  MsckfPolicy(const EstimatorOptions& options, int gn_steps);
  PolicyTiming Update(const StereoFrame& frame, StateId new_state, Window& window) override;
  const MsckfCounts& counts() const { return counts_; }

 private:
  using Observation = std::pair<StateId, Eigen::Vector3d>;

  std::vector<StateId> LeavingStates(const Window& window) const;
  std::vector<LandmarkId> MatureTracks(const StereoFrame& frame, const std::vector<StateId>& leaving);
  std::vector<LandmarkId> AddTriangulated(const std::vector<LandmarkId>& mature, Window& window);
  void ForgetObservationsOf(const std::vector<StateId>& leaving);

  EstimatorOptions options_;
  int gn_steps_;
  std::map<LandmarkId, std::vector<Observation>> tracks_;  ///< unused observations, oldest first
  MsckfCounts counts_;
};

}  // namespace vio
