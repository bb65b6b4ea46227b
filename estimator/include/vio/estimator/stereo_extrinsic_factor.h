#pragma once
// Rectified stereo reprojection factor with a correction of the camera-IMU
// extrinsics T_b_cl as a parameter (the stereo baseline is kept).
//
// Parameter blocks: pose [p_w_b, q_w_b] (7), landmark p_w_l (3), extrinsic
// correction c = (dtheta, dp) (6, Euclidean, small). The corrected rig is
//   R_b_c' = R_b_c Exp(dtheta),   p_b_c' = p_b_c + dp
// (CorrectedStereo) and the residual is StereoFactor's with that rig. With
// p_c = R_b_c'^T (p_b - p_b_c') and Jr the SO(3) right Jacobian:
//   dp_c/ddtheta = [p_c]x Jr(dtheta),   dp_c/ddp = -R_b_c'^T
// and the pose and landmark Jacobians are StereoFactor's at the corrected rig.
// With c = 0 the residual is StereoFactor's.
#include <memory>

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>

#include "vio/estimator/stereo_factor.h"
#include "vio/estimator/types.h"
#include "vio/marginalization/tangent_cost_function.h"

namespace vio {

/// The rig with its extrinsics corrected by c = (dtheta, dp) as above.
RectifiedStereo CorrectedStereo(const RectifiedStereo& stereo, const Eigen::Matrix<double, 6, 1>& correction);

class StereoExtrinsicFactor final : public ceres::SizedCostFunction<3, 7, 3, 6>,
                                    public marginalization::TangentCostFunction {
 public:
  /// z_px = (u_L, u_R, v) rectified [px]; stereo: the given rig, shared (not null); sigma_px > 0.
  StereoExtrinsicFactor(const Eigen::Vector3d& z_px, std::shared_ptr<const RectifiedStereo> stereo, double sigma_px);
  /// As above with a copy of `stereo` of its own.
  StereoExtrinsicFactor(const Eigen::Vector3d& z_px, const RectifiedStereo& stereo, double sigma_px);

  /// The residual and Jacobians (ambient, or on the tangents) of a measurement z_px with noise
  /// sigma_px at the given rig `stereo`: what Evaluate and EvaluateOnTangents compute.
  static bool EvaluateAt(const RectifiedStereo& stereo, const Eigen::Vector3d& z_px, double sigma_px,
                         double const* const* parameters, double* residuals, double** jacobians, bool on_tangents);

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  bool EvaluateOnTangents(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:

  Eigen::Vector3d z_px_;
  std::shared_ptr<const RectifiedStereo> stereo_;
  double sigma_px_;
};

}  // namespace vio
