#include "vio/estimator/stereo_factor.h"

#include <sstream>
#include <stdexcept>
#include <utility>

#include "vio/estimator/pose_manifold.h"
#include "vio/estimator/so3.h"

namespace vio {
namespace {

/// A landmark expressed in the body and in the rectified left camera.
struct CameraPoint {
  Eigen::Vector3d p_b;    ///< landmark in body [m]
  Eigen::Vector3d p_c;    ///< landmark in the rectified left camera [m]
  Eigen::Matrix3d R_c_b;  ///< rotation body -> camera
};

CameraPoint ToCamera(const RectifiedStereo& stereo, const Eigen::Vector3d& p_w_b,
                     const Eigen::Matrix3d& R_w_b, const Eigen::Vector3d& p_w_l) {
  CameraPoint point;
  point.R_c_b = stereo.T_b_cl.rotation().transpose();
  point.p_b = R_w_b.transpose() * (p_w_l - p_w_b);
  point.p_c = point.R_c_b * (point.p_b - stereo.T_b_cl.translation());
  return point;
}

Eigen::Vector3d ProjectCameraPoint(const RectifiedStereo& stereo, const Eigen::Vector3d& p_c) {
  const double inverse_z = 1.0 / p_c.z();
  return Eigen::Vector3d(stereo.f * p_c.x() * inverse_z + stereo.cx,
                         stereo.f * (p_c.x() - stereo.baseline) * inverse_z + stereo.cx,
                         stereo.f * p_c.y() * inverse_z + stereo.cy);
}

/// dh / dp_c.
Eigen::Matrix3d ProjectionJacobian(const RectifiedStereo& stereo, const Eigen::Vector3d& p_c) {
  const double inverse_z = 1.0 / p_c.z();
  const double f_z = stereo.f * inverse_z;
  Eigen::Matrix3d J;
  J << f_z, 0.0, -f_z * p_c.x() * inverse_z,
       f_z, 0.0, -f_z * (p_c.x() - stereo.baseline) * inverse_z,
       0.0, f_z, -f_z * p_c.y() * inverse_z;
  return J;
}

}  // namespace

StereoFactor::StereoFactor(const Eigen::Vector3d& z_px, std::shared_ptr<const RectifiedStereo> stereo,
                           double sigma_px)
    : z_px_(z_px), stereo_(std::move(stereo)), inverse_sigma_(0.0) {
  if (stereo_ == nullptr) throw std::invalid_argument("StereoFactor: the rig (stereo) is null");
  if (!(sigma_px > 0.0)) {
    std::ostringstream message;
    message << "StereoFactor: sigma_px must be > 0, got " << sigma_px;
    throw std::invalid_argument(message.str());
  }
  inverse_sigma_ = 1.0 / sigma_px;
}

StereoFactor::StereoFactor(const Eigen::Vector3d& z_px, const RectifiedStereo& stereo, double sigma_px)
    : StereoFactor(z_px, std::make_shared<const RectifiedStereo>(stereo), sigma_px) {}

ceres::CostFunction* StereoFactor::Create(const Eigen::Vector3d& z_px,
                                          std::shared_ptr<const RectifiedStereo> stereo, double sigma_px) {
  return new StereoFactor(z_px, std::move(stereo), sigma_px);
}

ceres::CostFunction* StereoFactor::Create(const Eigen::Vector3d& z_px,
                                          const RectifiedStereo& stereo, double sigma_px) {
  return new StereoFactor(z_px, stereo, sigma_px);
}

bool StereoFactor::Project(const RectifiedStereo& stereo, const Eigen::Vector3d& p_w_b,
                           const Eigen::Quaterniond& q_w_b, const Eigen::Vector3d& p_w_l,
                           Eigen::Vector3d* z_px) {
  const CameraPoint point = ToCamera(stereo, p_w_b, q_w_b.normalized().toRotationMatrix(), p_w_l);
  if (point.p_c.z() < kMinDepth) return false;
  *z_px = ProjectCameraPoint(stereo, point.p_c);
  return true;
}

bool StereoFactor::Evaluate(double const* const* parameters, double* residuals,
                            double** jacobians) const {
  return EvaluateAt(*stereo_, z_px_, inverse_sigma_, parameters, residuals, jacobians, /*on_tangents=*/false);
}

bool StereoFactor::EvaluateOnTangents(double const* const* parameters, double* residuals,
                                      double** jacobians) const {
  return EvaluateAt(*stereo_, z_px_, inverse_sigma_, parameters, residuals, jacobians, /*on_tangents=*/true);
}

bool StereoFactor::EvaluateAt(const RectifiedStereo& stereo, const Eigen::Vector3d& z_px, double inverse_sigma,
                              double const* const* parameters, double* residuals, double** jacobians,
                              bool on_tangents) {
  const Eigen::Map<const Eigen::Vector3d> p_w_b(parameters[0]);
  const Eigen::Quaterniond q_w_b =
      Eigen::Map<const Eigen::Quaterniond>(parameters[0] + 3).normalized();
  const Eigen::Map<const Eigen::Vector3d> p_w_l(parameters[1]);
  const Eigen::Matrix3d R_w_b = q_w_b.toRotationMatrix();

  const CameraPoint point = ToCamera(stereo, p_w_b, R_w_b, p_w_l);
  if (point.p_c.z() < kMinDepth) return false;
  Eigen::Map<Eigen::Vector3d>{residuals} =
      inverse_sigma * (z_px - ProjectCameraPoint(stereo, point.p_c));
  if (jacobians == nullptr) return true;

  // d e / d p_c, then chained into the blocks.
  const Eigen::Matrix3d de_dp_c = -inverse_sigma * ProjectionJacobian(stereo, point.p_c);
  const Eigen::Matrix3d R_c_w = point.R_c_b * R_w_b.transpose();
  if (jacobians[0] != nullptr) {
    Eigen::Matrix<double, 3, 6> J_tangent;
    J_tangent.leftCols<3>() = -de_dp_c * R_c_w;
    J_tangent.rightCols<3>() = de_dp_c * point.R_c_b * so3::Hat(point.p_b);
    if (on_tangents) {
      Eigen::Map<Eigen::Matrix<double, 3, 6, Eigen::RowMajor>>{jacobians[0]} = J_tangent;
    } else {
      PoseJacobianToAmbient<3>(J_tangent, q_w_b, jacobians[0]);
    }
  }
  if (jacobians[1] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>{jacobians[1]} = de_dp_c * R_c_w;
  }
  return true;
}

}  // namespace vio
