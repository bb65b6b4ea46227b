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
