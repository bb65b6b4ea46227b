#pragma once
// Rectified stereo geometry (paper §5.4): projection and triangulation of a
// point with the pinhole shared by both rectified cameras.
//   u_L = f x / z + cx,   u_R = f (x - b) / z + cx,   v = f y / z + cy
// so disparity d = u_L - u_R = f b / z.
#include <optional>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "vio/estimator/types.h"

namespace vio {

/// The point in the rectified left camera that projects to z = (u_L, u_R, v),
/// or nothing when the disparity is below `min_disparity_px`.
std::optional<Eigen::Vector3d> TriangulateRectified(const Eigen::Vector3d& z_px, const RectifiedStereo& stereo,
                                                    double min_disparity_px);

/// (u_L, u_R, v) of a point in the rectified left camera (z > 0 assumed).
Eigen::Vector3d ProjectRectified(const Eigen::Vector3d& p_cl, const RectifiedStereo& stereo);

/// dh/dp_cl of ProjectRectified at p_cl (z > 0 assumed):
///   f / z [[1, 0, -x / z], [1, 0, -(x - b) / z], [0, 1, -y / z]].
Eigen::Matrix3d RectifiedProjectionJacobian(const Eigen::Vector3d& p_cl, const RectifiedStereo& stereo);

/// The rectified left camera's motion at a frame, in its own frame: angular rate omega_c [rad/s]
/// and linear velocity v_c [m/s]. A static point p_c moves as dp_c/dt = -omega_c x p_c - v_c.
struct CameraMotion {
  Eigen::Vector3d omega_c = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_c = Eigen::Vector3d::Zero();
};

/// The camera's motion of a body with orientation q_w_b, velocity v_w_b [m/s] and angular rate
/// omega_b [rad/s, body]: omega_c = R_c_b omega_b, v_c = R_c_b (R_b_w v_w_b + omega_b x p_b_c).
CameraMotion CameraMotionOf(const RectifiedStereo& stereo, const Eigen::Quaterniond& q_w_b, const Eigen::Vector3d& v_w_b,
                            const Eigen::Vector3d& omega_b);

/// d(u_L, u_R, v)/dt [px/s] of the static point p_cl (rectified left camera, z > 0) seen by a
/// camera moving as `motion`: v = dh/dp_c (-omega_c x p_c - v_c). With d_dp_c, also dv/dp_c
/// (the projection's second derivative along dp_c/dt, plus dh/dp_c (-[omega_c]x)).
Eigen::Vector3d ImageVelocity(const Eigen::Vector3d& p_cl, const CameraMotion& motion, const RectifiedStereo& stereo,
                              Eigen::Matrix3d* d_dp_c = nullptr);

}  // namespace vio
