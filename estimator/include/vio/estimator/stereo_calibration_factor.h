#pragma once
// Rectified stereo reprojection factor with the window's calibration blocks:
// the camera-IMU time offset (stereo_time_offset_factor.h) and the extrinsic
// correction of the rig (stereo_extrinsic_factor.h), each optional.
//
// Parameter blocks: pose (7), landmark (3), then t_d (1) [s] when the time
// offset is estimated, then c = (dtheta, dp) (6) when the extrinsics are. The
// residual is StereoExtrinsicFactor's (StereoFactor's without c) plus
// (t_d - t_a) v / sigma_px with the time offset; each block's Jacobian is that
// of the factor that has it, so with one block the residual and Jacobians are
// the single-block factor's.
#include <ceres/cost_function.h>

#include <Eigen/Core>

#include "vio/estimator/stereo_extrinsic_factor.h"
#include "vio/estimator/stereo_factor.h"
#include "vio/estimator/types.h"
#include "vio/marginalization/tangent_cost_function.h"

namespace vio {

class StereoCalibrationFactor final : public ceres::CostFunction, public marginalization::TangentCostFunction {
 public:
  /// The time offset's part (when estimated): the image velocity of z_px [px/s] and t_a [s].
  struct TimeOffset {
    Eigen::Vector3d velocity_px_s = Eigen::Vector3d::Zero();
    double applied_offset_s = 0;
  };
  /// time_offset: null when t_d is no block; extrinsics: whether c is a block. sigma_px > 0.
  StereoCalibrationFactor(const Eigen::Vector3d& z_px, const RectifiedStereo& stereo, double sigma_px,
                          const TimeOffset* time_offset, bool extrinsics);

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  bool EvaluateOnTangents(double const* const* parameters, double* residuals, double** jacobians) const override;

 private:
  bool EvaluateImpl(double const* const* parameters, double* residuals, double** jacobians, bool on_tangents) const;

  StereoFactor plain_;
  StereoExtrinsicFactor extrinsic_;
  bool has_time_offset_;
  bool has_extrinsics_;
  Eigen::Vector3d whitened_velocity_ = Eigen::Vector3d::Zero();  ///< v / sigma_px
  double applied_offset_s_ = 0;
};

}  // namespace vio
