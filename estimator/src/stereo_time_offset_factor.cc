#include "vio/estimator/stereo_time_offset_factor.h"

namespace vio {

StereoTimeOffsetFactor::StereoTimeOffsetFactor(const Eigen::Vector3d& z_px, const Eigen::Vector3d& velocity_px_s,
                                               double applied_offset_s, const RectifiedStereo& stereo,
                                               double sigma_px)
    : stereo_(z_px, stereo, sigma_px),  // throws on sigma_px <= 0
      whitened_velocity_(velocity_px_s / sigma_px),
      applied_offset_s_(applied_offset_s) {}

bool StereoTimeOffsetFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  return EvaluateImpl(parameters, residuals, jacobians, /*on_tangents=*/false);
}

bool StereoTimeOffsetFactor::EvaluateOnTangents(double const* const* parameters, double* residuals,
                                                double** jacobians) const {
  return EvaluateImpl(parameters, residuals, jacobians, /*on_tangents=*/true);
}

bool StereoTimeOffsetFactor::EvaluateImpl(double const* const* parameters, double* residuals, double** jacobians,
                                          bool on_tangents) const {
  double* stereo_jacobians[2] = {nullptr, nullptr};
  if (jacobians != nullptr) {
    stereo_jacobians[0] = jacobians[0];
    stereo_jacobians[1] = jacobians[1];
  }
  double** inner = jacobians != nullptr ? stereo_jacobians : nullptr;
  const bool ok = on_tangents ? stereo_.EvaluateOnTangents(parameters, residuals, inner)
                              : stereo_.Evaluate(parameters, residuals, inner);
  if (!ok) return false;
  Eigen::Map<Eigen::Vector3d>{residuals} += (parameters[2][0] - applied_offset_s_) * whitened_velocity_;
  if (jacobians != nullptr && jacobians[2] != nullptr) Eigen::Map<Eigen::Vector3d>{jacobians[2]} = whitened_velocity_;
  return true;
}

}  // namespace vio
