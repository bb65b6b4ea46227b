#include "vio/estimator/stereo_extrinsic_factor.h"

#include <cstring>
#include <stdexcept>
#include <utility>

#include "vio/estimator/so3.h"

namespace vio {
namespace {

// The corrected rig and Jr(dtheta) of one (rig, correction): every observation of an evaluation
// shares its c, so they are made once per thread and change of c, not once per residual (their
// sines and cosines were a tenth of a run's added cost). Keyed on the bits: the values are those
// computed per residual, to the last bit.
struct CorrectedRig {
  RectifiedStereo given;
  Eigen::Matrix<double, 6, 1> correction = Eigen::Matrix<double, 6, 1>::Zero();
  RectifiedStereo rig;
  Eigen::Matrix3d right_jacobian = Eigen::Matrix3d::Identity();
  bool valid = false;
};

bool SameBits(const RectifiedStereo& a, const RectifiedStereo& b) {
  return std::memcmp(&a.f, &b.f, sizeof(double)) == 0 && std::memcmp(&a.cx, &b.cx, sizeof(double)) == 0 &&
         std::memcmp(&a.cy, &b.cy, sizeof(double)) == 0 && std::memcmp(&a.baseline, &b.baseline, sizeof(double)) == 0 &&
         std::memcmp(a.T_b_cl.matrix().data(), b.T_b_cl.matrix().data(), 16 * sizeof(double)) == 0;
}

const CorrectedRig& CorrectedRigOf(const RectifiedStereo& given, const Eigen::Matrix<double, 6, 1>& correction) {
  thread_local CorrectedRig cached;
  if (!cached.valid || std::memcmp(cached.correction.data(), correction.data(), 6 * sizeof(double)) != 0 ||
      !SameBits(cached.given, given)) {
    cached.given = given;
    cached.correction = correction;
    cached.rig = CorrectedStereo(given, correction);
    cached.right_jacobian = so3::RightJacobian(correction.head<3>());
    cached.valid = true;
  }
  return cached;
}

}  // namespace

RectifiedStereo CorrectedStereo(const RectifiedStereo& stereo, const Eigen::Matrix<double, 6, 1>& correction) {
  RectifiedStereo corrected = stereo;
  corrected.T_b_cl.linear() = stereo.T_b_cl.linear() * so3::Exp(correction.head<3>());
  corrected.T_b_cl.translation() = stereo.T_b_cl.translation() + correction.tail<3>();
  return corrected;
}

StereoExtrinsicFactor::StereoExtrinsicFactor(const Eigen::Vector3d& z_px, std::shared_ptr<const RectifiedStereo> stereo,
                                             double sigma_px)
    : z_px_(z_px), stereo_(std::move(stereo)), sigma_px_(sigma_px) {
  if (stereo_ == nullptr) throw std::invalid_argument("StereoExtrinsicFactor: the rig (stereo) is null");
  if (!(sigma_px > 0.0)) throw std::invalid_argument("StereoExtrinsicFactor: sigma_px must be > 0");
}

StereoExtrinsicFactor::StereoExtrinsicFactor(const Eigen::Vector3d& z_px, const RectifiedStereo& stereo,
                                             double sigma_px)
    : StereoExtrinsicFactor(z_px, std::make_shared<const RectifiedStereo>(stereo), sigma_px) {}

bool StereoExtrinsicFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  return EvaluateAt(*stereo_, z_px_, sigma_px_, parameters, residuals, jacobians, /*on_tangents=*/false);
}

bool StereoExtrinsicFactor::EvaluateOnTangents(double const* const* parameters, double* residuals,
                                               double** jacobians) const {
  return EvaluateAt(*stereo_, z_px_, sigma_px_, parameters, residuals, jacobians, /*on_tangents=*/true);
}

bool StereoExtrinsicFactor::EvaluateAt(const RectifiedStereo& stereo, const Eigen::Vector3d& z_px, double sigma_px,
                                       double const* const* parameters, double* residuals, double** jacobians,
                                       bool on_tangents) {
  const Eigen::Map<const Eigen::Matrix<double, 6, 1>> correction(parameters[2]);
  const CorrectedRig& corrected = CorrectedRigOf(stereo, correction);
  const RectifiedStereo& rig = corrected.rig;
  const bool want_extrinsic = jacobians != nullptr && jacobians[2] != nullptr;
  // The landmark Jacobian J_l = -(1/sigma) dh/dp_c R_c_w gives -(1/sigma) dh/dp_c = J_l R_w_c.
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> landmark_jacobian;
  double* stereo_jacobians[2] = {nullptr, nullptr};
  if (jacobians != nullptr) {
    stereo_jacobians[0] = jacobians[0];
    stereo_jacobians[1] = jacobians[1];
    if (stereo_jacobians[1] == nullptr && want_extrinsic) stereo_jacobians[1] = landmark_jacobian.data();
  }
  double** inner = jacobians != nullptr ? stereo_jacobians : nullptr;
  const bool ok = StereoFactor::EvaluateAt(rig, z_px, 1.0 / sigma_px, parameters, residuals, inner, on_tangents);
  if (!ok || !want_extrinsic) return ok;
  if (jacobians[1] != nullptr) landmark_jacobian = Eigen::Map<const decltype(landmark_jacobian)>(jacobians[1]);
  const Eigen::Quaterniond q_w_b(parameters[0][6], parameters[0][3], parameters[0][4], parameters[0][5]);
  const Eigen::Matrix3d R_w_c = q_w_b.normalized().toRotationMatrix() * rig.T_b_cl.linear();
  const Eigen::Vector3d p_w_l(parameters[1][0], parameters[1][1], parameters[1][2]);
  const Eigen::Vector3d p_w_b(parameters[0][0], parameters[0][1], parameters[0][2]);
  const Eigen::Vector3d p_c = R_w_c.transpose() * (p_w_l - p_w_b) -
                              rig.T_b_cl.linear().transpose() * rig.T_b_cl.translation();
  const Eigen::Matrix3d de_dpc = landmark_jacobian * R_w_c;
  Eigen::Map<Eigen::Matrix<double, 3, 6, Eigen::RowMajor>> J(jacobians[2]);
  J.leftCols<3>() = de_dpc * so3::Hat(p_c) * corrected.right_jacobian;
  J.rightCols<3>() = -de_dpc * rig.T_b_cl.linear().transpose();
  return true;
}

}  // namespace vio
