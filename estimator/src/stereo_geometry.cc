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

Eigen::Matrix3d RectifiedProjectionJacobian(const Eigen::Vector3d& p_cl, const RectifiedStereo& stereo) {
  const double inv_z = 1.0 / p_cl.z();
  const double f_z = stereo.f * inv_z;
  Eigen::Matrix3d J;
  J << f_z, 0.0, -f_z * p_cl.x() * inv_z,
       f_z, 0.0, -f_z * (p_cl.x() - stereo.baseline) * inv_z,
       0.0, f_z, -f_z * p_cl.y() * inv_z;
  return J;
}

CameraMotion CameraMotionOf(const RectifiedStereo& stereo, const Eigen::Quaterniond& q_w_b, const Eigen::Vector3d& v_w_b,
                            const Eigen::Vector3d& omega_b) {
  const Eigen::Matrix3d R_c_b = stereo.T_b_cl.linear().transpose();
  CameraMotion motion;
  motion.omega_c = R_c_b * omega_b;
  motion.v_c = R_c_b * (q_w_b.conjugate() * v_w_b + omega_b.cross(stereo.T_b_cl.translation()));
  return motion;
}

Eigen::Vector3d ImageVelocity(const Eigen::Vector3d& p_cl, const CameraMotion& motion, const RectifiedStereo& stereo,
                              Eigen::Matrix3d* d_dp_c) {
  const Eigen::Vector3d dp = -motion.omega_c.cross(p_cl) - motion.v_c;
  const Eigen::Matrix3d J = RectifiedProjectionJacobian(p_cl, stereo);
  if (d_dp_c != nullptr) {
    // d/dp_c of (dh/dp_c) dp at a fixed dp: row (f n / z) has gradient f (-dp_z / z^2) along n's
    // coordinate and f (-dp_n / z^2 + 2 n dp_z / z^3) along z, n = x, x - b, y.
    const double inv_z = 1.0 / p_cl.z();
    const double f_zz = stereo.f * inv_z * inv_z;
    const double n[3] = {p_cl.x(), p_cl.x() - stereo.baseline, p_cl.y()};
    const double dn[3] = {dp.x(), dp.x(), dp.y()};
    const int column[3] = {0, 0, 1};
    Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
    for (int row = 0; row < 3; ++row) {
      second(row, column[row]) = -f_zz * dp.z();
      second(row, 2) = f_zz * (-dn[row] + 2.0 * n[row] * dp.z() * inv_z);
    }
    Eigen::Matrix3d omega_hat;
    omega_hat << 0.0, -motion.omega_c.z(), motion.omega_c.y(),
                 motion.omega_c.z(), 0.0, -motion.omega_c.x(),
                 -motion.omega_c.y(), motion.omega_c.x(), 0.0;
    *d_dp_c = second - J * omega_hat;
  }
  return J * dp;
}

}  // namespace vio
