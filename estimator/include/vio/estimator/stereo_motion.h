#pragma once
// Body motion from stereo alone: each rectified stereo observation is a metric
// 3D point in its frame, so the relative pose of two frames is the rigid
// transform that best maps one frame's points of the shared landmarks onto
// the other's (weighted Kabsch / Umeyama without scale, re-fitted without
// outliers). No IMU, no prior: the dynamic initializer's visual half.
#include <optional>
#include <string>
#include <vector>

#include "vio/estimator/estimator_options.h"
#include "vio/estimator/types.h"

namespace vio {

/// The relative pose of two frames and how many landmarks support it.
struct StereoRelativePose {
  Eigen::Isometry3d T_a_b = Eigen::Isometry3d::Identity();  ///< frame b's body in frame a's body
  int inliers = 0;  ///< shared landmarks kept by the fit
  int shared = 0;   ///< shared landmarks with a stereo point in both frames
};

/// T_a_b from the landmarks a and b both see with disparity >= model.min_disparity_px and depth <=
/// model.max_depth_m; nothing when fewer than `min_landmarks` remain after outlier rejection (the
/// shared count is still reported through `shared` when not null).
std::optional<StereoRelativePose> RelativeStereoPose(const StereoFrame& a, const StereoFrame& b,
                                                     const RectifiedStereo& stereo, const ModelOptions& model,
                                                     int min_landmarks, int* shared = nullptr);

/// RelativeStereoPose refined by Gauss-Newton on the shared points' differences weighted by their
/// full stereo covariances (a point's depth error lies along its ray): the isotropic fit's rotation
/// is biased by that (about 1 deg over EuRoC-like motion), this one is not to first order.
std::optional<StereoRelativePose> WeightedRelativeStereoPose(const StereoFrame& a, const StereoFrame& b,
                                                             const RectifiedStereo& stereo, const ModelOptions& model,
                                                             int min_landmarks);

/// Body poses of every frame in the first frame's body (T_0_k, the first the identity), chained
/// from consecutive relative poses; `failure` names the first pair that did not give one.
struct StereoTrajectory {
  std::vector<Eigen::Isometry3d> T_0_k;
  std::string failure;  ///< empty on success
};
StereoTrajectory ChainStereoPoses(const std::vector<StereoFrame>& frames, const RectifiedStereo& stereo,
                                  const ModelOptions& model, int min_landmarks);

}  // namespace vio
