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

/// d(u_L, u_R, v)/dt [px/s] of a static point seen at z_px (stereo-triangulated; at max_depth_m
/// along its ray when its disparity is below min_disparity_px) from a body with orientation
/// q_w_b, velocity v_w_b [m/s] and angular rate omega_b [rad/s, body]: first order, from
/// dp_c/dt = R_c_b (-omega_b x p_b - R_b_w v_w_b).
Eigen::Vector3d ImageVelocity(const Eigen::Vector3d& z_px, const RectifiedStereo& stereo, const Eigen::Quaterniond& q_w_b,
                              const Eigen::Vector3d& v_w_b, const Eigen::Vector3d& omega_b, double min_disparity_px,
                              double max_depth_m);

}  // namespace vio
