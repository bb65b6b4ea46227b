#include "vio/estimator/stereo_calibration_factor.h"

#include <sstream>
#include <stdexcept>
#include <utility>

namespace vio {
namespace {

/// (dh/dp_c)^-1 of the rectified projection at p_c (b != 0): from the disparity's row,
/// dz = -z^2 / (f b) (du_L - du_R), then dx = (z / f) du_L + (x / z) dz, dy = (z / f) dv + (y / z) dz.
Eigen::Matrix3d InverseRectifiedProjectionJacobian(const Eigen::Vector3d& p_c, const RectifiedStereo& stereo) {
  const double z_f = p_c.z() / stereo.f;
  const double z_fb = z_f / stereo.baseline;
  Eigen::Matrix3d inverse;
  inverse << z_f - p_c.x() * z_fb, p_c.x() * z_fb, 0.0,
             -p_c.y() * z_fb, p_c.y() * z_fb, z_f,
             -p_c.z() * z_fb, p_c.z() * z_fb, 0.0;
  return inverse;
}

/// J <- chain J for a row-major 3 x N Jacobian.
template <int N>
void ChainInto(const Eigen::Matrix3d& chain, double* jacobian) {
  Eigen::Map<Eigen::Matrix<double, 3, N, Eigen::RowMajor>> J(jacobian);
  const Eigen::Matrix<double, 3, N, Eigen::RowMajor> chained = chain * J;
  J = chained;
}

}  // namespace

StereoCalibrationFactor::StereoCalibrationFactor(const Eigen::Vector3d& z_px,
                                                 std::shared_ptr<const RectifiedStereo> stereo, double sigma_px,
                                                 const TimeOffset* time_offset, bool extrinsics)
    : z_px_(z_px),
      stereo_(std::move(stereo)),
      sigma_px_(sigma_px),
      has_time_offset_(time_offset != nullptr),
      has_extrinsics_(extrinsics) {
  if (stereo_ == nullptr) throw std::invalid_argument("StereoCalibrationFactor: the rig (stereo) is null");
  if (!(sigma_px > 0.0)) {
    std::ostringstream message;
    message << "StereoCalibrationFactor: sigma_px must be > 0, got " << sigma_px;
    throw std::invalid_argument(message.str());
  }
  set_num_residuals(3);
  *mutable_parameter_block_sizes() = {7, 3};
  if (has_time_offset_) {
    mutable_parameter_block_sizes()->push_back(1);
    time_offset_ = *time_offset;
  }
  if (has_extrinsics_) mutable_parameter_block_sizes()->push_back(6);
}

StereoCalibrationFactor::StereoCalibrationFactor(const Eigen::Vector3d& z_px, const RectifiedStereo& stereo,
                                                 double sigma_px, const TimeOffset* time_offset, bool extrinsics)
    : StereoCalibrationFactor(z_px, std::make_shared<const RectifiedStereo>(stereo), sigma_px, time_offset,
                              extrinsics) {}

bool StereoCalibrationFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  return EvaluateImpl(parameters, residuals, jacobians, /*on_tangents=*/false);
}

bool StereoCalibrationFactor::EvaluateOnTangents(double const* const* parameters, double* residuals,
                                                 double** jacobians) const {
  return EvaluateImpl(parameters, residuals, jacobians, /*on_tangents=*/true);
}

bool StereoCalibrationFactor::EvaluateImpl(double const* const* parameters, double* residuals, double** jacobians,
                                           bool on_tangents) const {
  const int extrinsics = has_time_offset_ ? 3 : 2;
  const double* inner_parameters[3] = {parameters[0], parameters[1], has_extrinsics_ ? parameters[extrinsics] : nullptr};
  double* inner_jacobians[3] = {nullptr, nullptr, nullptr};
  if (jacobians != nullptr) {
    inner_jacobians[0] = jacobians[0];
    inner_jacobians[1] = jacobians[1];
    if (has_extrinsics_) inner_jacobians[2] = jacobians[extrinsics];
  }
  double** inner = jacobians != nullptr ? inner_jacobians : nullptr;
  const bool ok =
      has_extrinsics_
          ? StereoExtrinsicFactor::EvaluateAt(*stereo_, z_px_, sigma_px_, inner_parameters, residuals, inner, on_tangents)
          : StereoFactor::EvaluateAt(*stereo_, z_px_, 1.0 / sigma_px_, inner_parameters, residuals, inner, on_tangents);
  if (!ok || !has_time_offset_) return ok;
  AddTimeOffset(parameters, residuals, jacobians, on_tangents);
  return true;
}

void StereoCalibrationFactor::AddTimeOffset(double const* const* parameters, double* residuals, double** jacobians,
                                            bool on_tangents) const {
  const int time_offset = 2;
  const RectifiedStereo corrected =
      has_extrinsics_ ? CorrectedStereo(*stereo_, Eigen::Map<const Eigen::Matrix<double, 6, 1>>(parameters[3]))
                      : RectifiedStereo{};
  const RectifiedStereo& rig = has_extrinsics_ ? corrected : *stereo_;
  const Eigen::Map<const Eigen::Vector3d> p_w_b(parameters[0]);
  const Eigen::Quaterniond q_w_b = Eigen::Map<const Eigen::Quaterniond>(parameters[0] + 3).normalized();
  const Eigen::Map<const Eigen::Vector3d> p_w_l(parameters[1]);
  const Eigen::Vector3d p_b = q_w_b.conjugate() * (p_w_l - p_w_b);
  const Eigen::Vector3d p_c = rig.T_b_cl.linear().transpose() * (p_b - rig.T_b_cl.translation());
  Eigen::Matrix3d dv_dp_c;
  const Eigen::Vector3d velocity = ImageVelocity(p_c, time_offset_.motion, rig, jacobians != nullptr ? &dv_dp_c : nullptr);
  const double dt = parameters[time_offset][0] - time_offset_.applied_offset_s;
  Eigen::Map<Eigen::Vector3d>{residuals} += (dt / sigma_px_) * velocity;
  if (jacobians == nullptr) return;
  if (jacobians[time_offset] != nullptr) Eigen::Map<Eigen::Vector3d>{jacobians[time_offset]} = velocity / sigma_px_;
  if (dt == 0.0) return;
  // The blocks reach e through p_c only: de_h/dx = -(1/sigma) dh/dp_c dp_c/dx.
  const Eigen::Matrix3d chain =
      Eigen::Matrix3d::Identity() - dt * dv_dp_c * InverseRectifiedProjectionJacobian(p_c, rig);
  if (jacobians[0] != nullptr) {
    if (on_tangents) {
      ChainInto<6>(chain, jacobians[0]);
    } else {
      ChainInto<7>(chain, jacobians[0]);
    }
  }
  if (jacobians[1] != nullptr) ChainInto<3>(chain, jacobians[1]);
  if (has_extrinsics_ && jacobians[3] != nullptr) ChainInto<6>(chain, jacobians[3]);
}

}  // namespace vio
