#include "vio/estimator/pose_prior_factor.h"

#include <sstream>
#include <stdexcept>

#include "vio/estimator/pose_manifold.h"
#include "vio/estimator/so3.h"

namespace vio {

PosePriorFactor::PosePriorFactor(const Eigen::Vector3d& p_w_b_prior,
                                 const Eigen::Quaterniond& q_w_b_prior,
                                 const Matrix6d& sqrt_information)
    : p_w_b_prior_(p_w_b_prior),
      q_w_b_prior_(q_w_b_prior.normalized()),
      sqrt_information_(sqrt_information) {}

ceres::CostFunction* PosePriorFactor::Create(const Eigen::Vector3d& p_w_b_prior,
                                             const Eigen::Quaterniond& q_w_b_prior,
                                             const Matrix6d& sqrt_information) {
  return new PosePriorFactor(p_w_b_prior, q_w_b_prior, sqrt_information);
}

ceres::CostFunction* PosePriorFactor::Create(const Eigen::Vector3d& p_w_b_prior,
                                             const Eigen::Quaterniond& q_w_b_prior,
                                             double sigma_position_m, double sigma_rotation_rad) {
  if (!(sigma_position_m > 0.0) || !(sigma_rotation_rad > 0.0)) {
    std::ostringstream message;
    message << "PosePriorFactor: sigmas must be > 0, got position " << sigma_position_m
            << " m, rotation " << sigma_rotation_rad << " rad";
    throw std::invalid_argument(message.str());
  }
  Eigen::Matrix<double, 6, 1> inverse_sigmas;
  inverse_sigmas << Eigen::Vector3d::Constant(1.0 / sigma_position_m),
      Eigen::Vector3d::Constant(1.0 / sigma_rotation_rad);
  return new PosePriorFactor(p_w_b_prior, q_w_b_prior, inverse_sigmas.asDiagonal());
}

bool PosePriorFactor::Evaluate(double const* const* parameters, double* residuals,
                               double** jacobians) const {
  const Eigen::Map<const Eigen::Vector3d> p_w_b(parameters[0]);
  const Eigen::Quaterniond q_w_b =
      Eigen::Map<const Eigen::Quaterniond>(parameters[0] + 3).normalized();
  Eigen::Matrix<double, 6, 1> r;
  r.head<3>() = p_w_b - p_w_b_prior_;
  r.tail<3>() = so3::Log(q_w_b_prior_.conjugate() * q_w_b);
  Eigen::Map<Eigen::Matrix<double, 6, 1>>{residuals} = sqrt_information_ * r;
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    Matrix6d J = Matrix6d::Identity();
    J.bottomRightCorner<3, 3>() = so3::RightJacobianInverse(r.tail<3>());
    PoseJacobianToAmbient<6>(sqrt_information_ * J, q_w_b, jacobians[0]);
  }
  return true;
}

}  // namespace vio
