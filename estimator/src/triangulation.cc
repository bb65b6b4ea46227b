#include "vio/estimator/triangulation.h"

#include <vector>

#include <Eigen/Eigenvalues>
#include <glog/logging.h>

#include "vio/estimator/stereo_geometry.h"

namespace vio {
namespace {

// Residual (z - h) / sigma of one view (seen from the left camera at T_cl_w)
// and its Jacobian with respect to p_w; false when the point is not in front
// of the camera.
bool ViewResidual(const StereoView& view, const Eigen::Isometry3d& T_cl_w, const RectifiedStereo& stereo,
                  const Eigen::Vector3d& p_w, double inv_sigma, double min_depth, Eigen::Vector3d* r,
                  Eigen::Matrix3d* J) {
  const Eigen::Vector3d p = T_cl_w * p_w;
  if (p.z() < min_depth) return false;
  *r = (view.z_px - ProjectRectified(p, stereo)) * inv_sigma;
  const double f = stereo.f, iz = 1.0 / p.z(), iz2 = iz * iz;
  Eigen::Matrix3d d_h_d_p;
  d_h_d_p << f * iz, 0, -f * p.x() * iz2,
             f * iz, 0, -f * (p.x() - stereo.baseline) * iz2,
             0, f * iz, -f * p.y() * iz2;
  *J = -inv_sigma * d_h_d_p * T_cl_w.linear();
  return true;
}

// The stereo point of the view with the largest disparity, in world.
std::optional<Eigen::Vector3d> InitialGuess(const std::vector<StereoView>& views, const RectifiedStereo& stereo) {
  const StereoView* best = &views.front();
  for (const StereoView& v : views) {
    if (v.z_px[0] - v.z_px[1] > best->z_px[0] - best->z_px[1]) best = &v;
  }
  const std::optional<Eigen::Vector3d> p_cl = TriangulateRectified(best->z_px, stereo, 1e-3);
  if (!p_cl) return std::nullopt;
  return best->T_w_b * stereo.T_b_cl * *p_cl;
}

}  // namespace

TriangulationResult TriangulateMultiView(const std::vector<StereoView>& views, const RectifiedStereo& stereo,
                                         const TriangulationOptions& options) {
  CHECK(!views.empty()) << "triangulation without views";
  TriangulationResult result;
  std::optional<Eigen::Vector3d> p_w = InitialGuess(views, stereo);
  if (!p_w) return {std::nullopt, TriangulationFailure::kNoDisparity};
  const Eigen::Isometry3d T_cl_b = stereo.T_b_cl.inverse();
  // Each view's world-to-camera transform, once for every iteration.
  std::vector<Eigen::Isometry3d> T_cl_w;
  T_cl_w.reserve(views.size());
  for (const StereoView& view : views) T_cl_w.push_back(T_cl_b * view.T_w_b.inverse());
  const double inv_sigma = 1.0 / options.pixel_sigma;
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  Eigen::Vector3d r, g;
  Eigen::Matrix3d J;
  double max_error = 0;
  for (int it = 0; it <= options.iterations; ++it) {
    H.setZero();
    g.setZero();
    max_error = 0;
    for (std::size_t v = 0; v < views.size(); ++v) {
      if (!ViewResidual(views[v], T_cl_w[v], stereo, *p_w, inv_sigma, options.min_depth_m, &r, &J)) {
        return {std::nullopt, TriangulationFailure::kBehindCamera};
      }
      H += J.transpose() * J;
      g += J.transpose() * r;
      max_error = std::max(max_error, r.norm());
    }
    if (it == options.iterations) break;
    *p_w -= H.ldlt().solve(g);
  }
  result.max_error_sigma = max_error;
  if (max_error > options.max_reprojection_sigma) {
    result.failure = TriangulationFailure::kReprojection;
    return result;
  }
  const double min_information = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(H).eigenvalues()[0];
  if (!(min_information > 0) || 1.0 / std::sqrt(min_information) > options.max_position_sigma_m) {
    result.failure = TriangulationFailure::kIllConditioned;
    return result;
  }
  result.p_w = p_w;
  return result;
}

}  // namespace vio
