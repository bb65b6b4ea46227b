#pragma once
// Rectified stereo geometry (paper §5.4): projection and triangulation of a
// point with the pinhole shared by both rectified cameras.
//   u_L = f x / z + cx,   u_R = f (x - b) / z + cx,   v = f y / z + cy
// so disparity d = u_L - u_R = f b / z.
#include <optional>

#include "vio/estimator/types.h"

namespace vio {

/// The point in the rectified left camera that projects to z = (u_L, u_R, v),
/// or nothing when the disparity is below `min_disparity_px`.
std::optional<Eigen::Vector3d> TriangulateRectified(const Eigen::Vector3d& z_px, const RectifiedStereo& stereo,
                                                    double min_disparity_px);

/// (u_L, u_R, v) of a point in the rectified left camera (z > 0 assumed).
Eigen::Vector3d ProjectRectified(const Eigen::Vector3d& p_cl, const RectifiedStereo& stereo);

}  // namespace vio
