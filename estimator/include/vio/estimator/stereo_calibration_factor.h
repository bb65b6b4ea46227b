#pragma once
// Rectified stereo reprojection factor with the window's calibration blocks:
// the camera-IMU time offset t_d and the extrinsic correction c of the rig
// (stereo_extrinsic_factor.h), each optional.
//
// Parameter blocks: pose (7), landmark (3), then t_d (1) [s] when the time
// offset is estimated, then c = (dtheta, dp) (6) when the extrinsics are.
//
// The time offset (Qin & Shen 2018: the feature moved along its image
// velocity). An image stamped t was taken at IMU time t - t_d; the state of
// the observation sits at IMU time t - t_a (t_a: the offset applied to the
// frame's stamp when the state was made). The measurement moved to the
// state's time is z + (t_d - t_a) v, with v the image velocity of the
// landmark's estimate:
//   e = (z - h(x, l) + (t_d - t_a) v(x, l)) / sigma_px,
//   v(x, l) = dh/dp_c (-omega_c x p_c - v_c)   (ImageVelocity)
// where p_c is the landmark in the (corrected) left camera and h, the
// projection, StereoFactor's / StereoExtrinsicFactor's. The camera's angular
// rate omega_c and velocity v_c (its own frame; from the state's velocity and
// the bias-corrected gyro at the frame when it was made) are constants of the
// factor, not functions of the pose or speed/bias blocks: the factor stays on
// (pose, landmark, t_d, c). Jacobians: de/dt_d = v / sigma_px, and for a block
// x through p_c
//   de/dx = (-dh/dp_c + (t_d - t_a) dv/dp_c) dp_c/dx / sigma_px
//         = (I - (t_d - t_a) dv/dp_c (dh/dp_c)^-1) de_h/dx
// with de_h/dx the reprojection's (dh/dp_c is invertible for b != 0). With
// t_d = t_a the residual and Jacobians of the pose, landmark and c are the
// reprojection's; without t_d the factor is StereoExtrinsicFactor to the last bit.
#include <memory>

#include <ceres/cost_function.h>

#include <Eigen/Core>

#include "vio/estimator/stereo_extrinsic_factor.h"
#include "vio/estimator/stereo_factor.h"
#include "vio/estimator/stereo_geometry.h"
#include "vio/estimator/types.h"
#include "vio/marginalization/tangent_cost_function.h"

namespace vio {

class StereoCalibrationFactor final : public ceres::CostFunction, public marginalization::TangentCostFunction {
 public:
  /// The time offset's part (when estimated): the camera's motion at the state and t_a [s].
  struct TimeOffset {
    CameraMotion motion;
    double applied_offset_s = 0;
  };
  /// time_offset: null when t_d is no block; extrinsics: whether c is a block. stereo: the rig,
  /// shared (not null); sigma_px > 0.
  StereoCalibrationFactor(const Eigen::Vector3d& z_px, std::shared_ptr<const RectifiedStereo> stereo, double sigma_px,
                          const TimeOffset* time_offset, bool extrinsics);
  /// As above with a copy of `stereo` of its own.
  StereoCalibrationFactor(const Eigen::Vector3d& z_px, const RectifiedStereo& stereo, double sigma_px,
                          const TimeOffset* time_offset, bool extrinsics);

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  bool EvaluateOnTangents(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  bool EvaluateImpl(double const* const* parameters, double* residuals, double** jacobians, bool on_tangents) const;
  /// Adds the time offset's term to the reprojection's residual and Jacobians.
  void AddTimeOffset(double const* const* parameters, double* residuals, double** jacobians, bool on_tangents) const;

  Eigen::Vector3d z_px_;
  std::shared_ptr<const RectifiedStereo> stereo_;
  double sigma_px_;
  bool has_time_offset_;
  bool has_extrinsics_;
  TimeOffset time_offset_;
};

}  // namespace vio
