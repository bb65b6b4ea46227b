#include "vio/estimator/speed_bias_prior_factor.h"

#include <sstream>
#include <stdexcept>

namespace vio {

SpeedBiasPriorFactor::SpeedBiasPriorFactor(const Vector9d& speed_bias_prior,
                                           const Matrix9d& sqrt_information)
    : speed_bias_prior_(speed_bias_prior), sqrt_information_(sqrt_information) {}

ceres::CostFunction* SpeedBiasPriorFactor::Create(const Vector9d& speed_bias_prior,
                                                  const Matrix9d& sqrt_information) {
  return new SpeedBiasPriorFactor(speed_bias_prior, sqrt_information);
}

ceres::CostFunction* SpeedBiasPriorFactor::Create(const Vector9d& speed_bias_prior,
                                                  double sigma_velocity_m_s,
                                                  double sigma_gyro_bias_rad_s,
                                                  double sigma_accel_bias_m_s2) {
  if (!(sigma_velocity_m_s > 0.0) || !(sigma_gyro_bias_rad_s > 0.0) ||
      !(sigma_accel_bias_m_s2 > 0.0)) {
    std::ostringstream message;
    message << "SpeedBiasPriorFactor: sigmas must be > 0, got velocity " << sigma_velocity_m_s
            << " m/s, gyro bias " << sigma_gyro_bias_rad_s << " rad/s, accel bias "
            << sigma_accel_bias_m_s2 << " m/s^2";
    throw std::invalid_argument(message.str());
  }
  Vector9d inverse_sigmas;
  inverse_sigmas << Eigen::Vector3d::Constant(1.0 / sigma_velocity_m_s),
      Eigen::Vector3d::Constant(1.0 / sigma_gyro_bias_rad_s),
      Eigen::Vector3d::Constant(1.0 / sigma_accel_bias_m_s2);
  return new SpeedBiasPriorFactor(speed_bias_prior, inverse_sigmas.asDiagonal());
}

bool SpeedBiasPriorFactor::Evaluate(double const* const* parameters, double* residuals,
                                    double** jacobians) const {
  const Eigen::Map<const Vector9d> speed_bias(parameters[0]);
  Eigen::Map<Vector9d>{residuals} = sqrt_information_ * (speed_bias - speed_bias_prior_);
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 9, 9, Eigen::RowMajor>>{jacobians[0]} = sqrt_information_;
  }
  return true;
}

}  // namespace vio
