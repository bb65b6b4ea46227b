#include "vio/estimator/stereo_geometry.h"

namespace vio {

std::optional<Eigen::Vector3d> TriangulateRectified(const Eigen::Vector3d& z_px, const RectifiedStereo& stereo,
                                                    double min_disparity_px) {
  const double disparity = z_px[0] - z_px[1];
  if (!(disparity >= min_disparity_px) || disparity <= 0) return std::nullopt;
  const double depth = stereo.f * stereo.baseline / disparity;
  return Eigen::Vector3d((z_px[0] - stereo.cx) * depth / stereo.f, (z_px[2] - stereo.cy) * depth / stereo.f,
                         depth);
}

Eigen::Vector3d ProjectRectified(const Eigen::Vector3d& p_cl, const RectifiedStereo& stereo) {
  const double inv_z = 1.0 / p_cl.z();
  return Eigen::Vector3d(stereo.f * p_cl.x() * inv_z + stereo.cx,
                         stereo.f * (p_cl.x() - stereo.baseline) * inv_z + stereo.cx,
                         stereo.f * p_cl.y() * inv_z + stereo.cy);
}

}  // namespace vio

namespace vio {

Eigen::Vector3d ImageVelocity(const Eigen::Vector3d& z_px, const RectifiedStereo& stereo, const Eigen::Quaterniond& q_w_b,
                              const Eigen::Vector3d& v_w_b, const Eigen::Vector3d& omega_b, double min_disparity_px,
                              double max_depth_m) {
  Eigen::Vector3d p_c;
  if (const std::optional<Eigen::Vector3d> triangulated = TriangulateRectified(z_px, stereo, min_disparity_px)) {
    p_c = *triangulated;
  } else {
    p_c = max_depth_m * Eigen::Vector3d((z_px[0] - stereo.cx) / stereo.f, (z_px[2] - stereo.cy) / stereo.f, 1.0);
  }
  const Eigen::Matrix3d R_b_c = stereo.T_b_cl.linear();
  const Eigen::Vector3d p_b = R_b_c * p_c + stereo.T_b_cl.translation();
  const Eigen::Vector3d dp_c = R_b_c.transpose() * (-omega_b.cross(p_b) - q_w_b.conjugate() * v_w_b);
  const double inv_z = 1.0 / p_c.z();
  const double f_z = stereo.f * inv_z;
  Eigen::Matrix3d dh_dp_c;
  dh_dp_c << f_z, 0.0, -f_z * p_c.x() * inv_z,
             f_z, 0.0, -f_z * (p_c.x() - stereo.baseline) * inv_z,
             0.0, f_z, -f_z * p_c.y() * inv_z;
  return dh_dp_c * dp_c;
}

}  // namespace vio
