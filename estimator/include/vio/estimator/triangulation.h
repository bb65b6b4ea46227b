#pragma once
// Multi-view triangulation of one landmark from rectified stereo observations
// at known body poses: the stereo point of the view with the largest
// disparity, refined by Gauss-Newton on
//   sum_k || (z_k - h(T_w_b_k, p_w)) / sigma ||^2
// with the paper's §5.4 model h. Rejected (nothing returned) when a view sees
// it behind or too close to the camera, when a reprojection error exceeds the
// bound, or when the point is poorly constrained (its position standard
// deviation, from the Gauss-Newton information, exceeds the bound).
#include <optional>
#include <vector>

#include "vio/estimator/types.h"

namespace vio {

/// One observation of the landmark: the body pose and (u_L, u_R, v) [px].
struct StereoView {
  Eigen::Isometry3d T_w_b = Eigen::Isometry3d::Identity();
  Eigen::Vector3d z_px = Eigen::Vector3d::Zero();
};

struct TriangulationOptions {
  double pixel_sigma = 0.5;            ///< measurement noise of each coordinate [px]
  double max_reprojection_sigma = 5.0; ///< largest whitened error of any view [sigma]
  double max_position_sigma_m = 2.0;   ///< largest standard deviation of the point [m]
  double min_depth_m = 0.1;            ///< nearest depth in any view [m]
  int iterations = 5;                  ///< Gauss-Newton iterations [count]
};

/// Why a triangulation failed (for counts).
enum class TriangulationFailure { kNone, kNoDisparity, kBehindCamera, kReprojection, kIllConditioned };

struct TriangulationResult {
  std::optional<Eigen::Vector3d> p_w;  ///< the point [m], when accepted
  TriangulationFailure failure = TriangulationFailure::kNone;
  /// Largest whitened reprojection error of the refined point over the views
  /// [sigma] (set when the refinement ran: accepted, kReprojection, kIllConditioned).
  double max_error_sigma = 0.0;
};

TriangulationResult TriangulateMultiView(const std::vector<StereoView>& views, const RectifiedStereo& stereo,
                                         const TriangulationOptions& options);

}  // namespace vio
