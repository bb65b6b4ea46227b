#include "vio/estimator/stereo_calibration_factor.h"

namespace vio {

StereoCalibrationFactor::StereoCalibrationFactor(const Eigen::Vector3d& z_px, const RectifiedStereo& stereo,
                                                 double sigma_px, const TimeOffset* time_offset, bool extrinsics)
    : plain_(z_px, stereo, sigma_px),  // throws on sigma_px <= 0
      extrinsic_(z_px, stereo, sigma_px),
      has_time_offset_(time_offset != nullptr),
      has_extrinsics_(extrinsics) {
  set_num_residuals(3);
  *mutable_parameter_block_sizes() = {7, 3};
  if (has_time_offset_) {
    mutable_parameter_block_sizes()->push_back(1);
    whitened_velocity_ = time_offset->velocity_px_s / sigma_px;
    applied_offset_s_ = time_offset->applied_offset_s;
  }
  if (has_extrinsics_) mutable_parameter_block_sizes()->push_back(6);
}

bool StereoCalibrationFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  return EvaluateImpl(parameters, residuals, jacobians, /*on_tangents=*/false);
}

bool StereoCalibrationFactor::EvaluateOnTangents(double const* const* parameters, double* residuals,
                                                 double** jacobians) const {
  return EvaluateImpl(parameters, residuals, jacobians, /*on_tangents=*/true);
}

bool StereoCalibrationFactor::EvaluateImpl(double const* const* parameters, double* residuals, double** jacobians,
                                           bool on_tangents) const {
  const int time_offset = 2;
  const int extrinsics = has_time_offset_ ? 3 : 2;
  const double* inner_parameters[3] = {parameters[0], parameters[1], has_extrinsics_ ? parameters[extrinsics] : nullptr};
  double* inner_jacobians[3] = {nullptr, nullptr, nullptr};
  if (jacobians != nullptr) {
    inner_jacobians[0] = jacobians[0];
    inner_jacobians[1] = jacobians[1];
    if (has_extrinsics_) inner_jacobians[2] = jacobians[extrinsics];
  }
  double** inner = jacobians != nullptr ? inner_jacobians : nullptr;
  const ceres::CostFunction& stereo = has_extrinsics_ ? static_cast<const ceres::CostFunction&>(extrinsic_) : plain_;
  const auto& tangent = has_extrinsics_ ? static_cast<const marginalization::TangentCostFunction&>(extrinsic_) : plain_;
  const bool ok = on_tangents ? tangent.EvaluateOnTangents(inner_parameters, residuals, inner)
                              : stereo.Evaluate(inner_parameters, residuals, inner);
  if (!ok || !has_time_offset_) return ok;
  Eigen::Map<Eigen::Vector3d>{residuals} += (parameters[time_offset][0] - applied_offset_s_) * whitened_velocity_;
  if (jacobians != nullptr && jacobians[time_offset] != nullptr) {
    Eigen::Map<Eigen::Vector3d>{jacobians[time_offset]} = whitened_velocity_;
  }
  return true;
}

}  // namespace vio
