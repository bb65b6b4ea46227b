#pragma once
// Rectified stereo reprojection factor (paper §5.4).
//
// Parameter blocks: pose [p_w_b, q_w_b] (7), landmark p_w_l (3).
// With T_b_cl = (R_b_c, p_b_c) the rectified left camera in the body:
//   p_b = R_w_b^T (p_w_l - p_w_b),   p_c = R_b_c^T (p_b - p_b_c) = (x, y, z)
//   h   = (u_L, u_R, v) = (f x / z + cx,  f (x - b) / z + cx,  f y / z + cy)
//   e   = (z_px - h) / sigma_px
// (the right camera sits at +b along the left camera's x axis). Jacobians
// (pose tangent [dp, dtheta], q <- q Exp(dtheta)):
//   dh/dp_c = f / z [[1, 0, -x / z], [1, 0, -(x - b) / z], [0, 1, -y / z]]
//   dp_c/dp_w_l = R_c_w,  dp_c/dp_w_b = -R_c_w,  dp_c/dtheta = R_b_c^T [p_b]x
//   de/d. = -(1 / sigma_px) dh/dp_c dp_c/d.
// Evaluate returns false (Ceres rejects the step) when the landmark depth z
// is below kMinDepth. No robust loss inside: the caller adds a
// ceres::LossFunction. The rig is held by shared pointer: the factors of a
// window share its one rig (a copy is 160 B, most of a factor).
#include <memory>

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "vio/marginalization/tangent_cost_function.h"
#include "vio/estimator/types.h"

namespace vio {

class StereoFactor final : public ceres::SizedCostFunction<3, 7, 3>, public marginalization::TangentCostFunction {
 public:
  /// Smallest depth [m] in the left camera that Evaluate accepts.
  static constexpr double kMinDepth = 1e-3;

  /// z_px = (u_L, u_R, v) rectified [px]; stereo: the rig, shared (not null); sigma_px > 0
  /// isotropic noise [px].
  StereoFactor(const Eigen::Vector3d& z_px, std::shared_ptr<const RectifiedStereo> stereo, double sigma_px);
  /// As above with a copy of `stereo` of its own.
  StereoFactor(const Eigen::Vector3d& z_px, const RectifiedStereo& stereo, double sigma_px);

  static ceres::CostFunction* Create(const Eigen::Vector3d& z_px, std::shared_ptr<const RectifiedStereo> stereo,
                                     double sigma_px);
  static ceres::CostFunction* Create(const Eigen::Vector3d& z_px, const RectifiedStereo& stereo,
                                     double sigma_px);

  /// The residual and Jacobians (ambient, or on the tangents) of a measurement z_px with noise
  /// 1 / inverse_sigma at `stereo`: what Evaluate and EvaluateOnTangents compute.
  static bool EvaluateAt(const RectifiedStereo& stereo, const Eigen::Vector3d& z_px, double inverse_sigma,
                         double const* const* parameters, double* residuals, double** jacobians, bool on_tangents);

  /// h(T_w_b, p_w_l): predicted (u_L, u_R, v) [px]; false (and *z_px
  /// untouched) when the depth in the left camera is below kMinDepth.
  static bool Project(const RectifiedStereo& stereo, const Eigen::Vector3d& p_w_b,
                      const Eigen::Quaterniond& q_w_b, const Eigen::Vector3d& p_w_l,
                      Eigen::Vector3d* z_px);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;
  bool EvaluateOnTangents(double const* const* parameters, double* residuals,
                          double** jacobians) const override;

 private:
  Eigen::Vector3d z_px_;
  std::shared_ptr<const RectifiedStereo> stereo_;
  double inverse_sigma_;
};

}  // namespace vio
