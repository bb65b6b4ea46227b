#pragma once
// Rectified stereo reprojection factor with the camera-IMU time offset as a
// parameter (Qin & Shen 2018, "Online temporal calibration for monocular
// visual-inertial systems": the feature moved along its image velocity).
//
// Parameter blocks: pose [p_w_b, q_w_b] (7), landmark p_w_l (3), time offset
// t_d (1) [s]. An image stamped t was taken at IMU time t - t_d. The state of
// the observation sits at IMU time t - t_a (t_a: the offset the estimator
// applied to the frame's stamp when it made the state, the estimate then), so
// the measurement, moved to the state's time along the feature's image
// velocity v = (du_L, du_R, dv)/dt [px/s], is z + (t_d - t_a) v:
//   e = (z + (t_d - t_a) v - h(T_w_b, p_w_l)) / sigma_px
// with h the StereoFactor's projection: the pose and landmark Jacobians are
// StereoFactor's, de/dt_d = v / sigma_px. With t_d = t_a the residual is
// StereoFactor's.
#include <ceres/sized_cost_function.h>

#include <Eigen/Core>

#include "vio/estimator/stereo_factor.h"
#include "vio/estimator/types.h"
#include "vio/marginalization/tangent_cost_function.h"

namespace vio {

class StereoTimeOffsetFactor final : public ceres::SizedCostFunction<3, 7, 3, 1>,
                                     public marginalization::TangentCostFunction {
 public:
  /// velocity_px_s: the image velocity of z_px [px/s]; applied_offset_s: t_a [s].
  StereoTimeOffsetFactor(const Eigen::Vector3d& z_px, const Eigen::Vector3d& velocity_px_s,
                         double applied_offset_s, const RectifiedStereo& stereo, double sigma_px);

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  bool EvaluateOnTangents(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  bool EvaluateImpl(double const* const* parameters, double* residuals, double** jacobians, bool on_tangents) const;

  StereoFactor stereo_;
  Eigen::Vector3d whitened_velocity_;  ///< v / sigma_px
  double applied_offset_s_;
};

}  // namespace vio
