#pragma once
// Prior on one speed-and-bias block [v_w_b, b_g, b_a] (9, Euclidean).
//
//   e = S (x - x0),   d e / d x = S   (S: 9x9 sqrt information).
#include <ceres/sized_cost_function.h>

#include <Eigen/Core>

namespace vio {

class SpeedBiasPriorFactor final : public ceres::SizedCostFunction<9, 9> {
 public:
  using Vector9d = Eigen::Matrix<double, 9, 1>;
  using Matrix9d = Eigen::Matrix<double, 9, 9>;

  /// sqrt_information: S with S^T S = Sigma^-1 over [v_w_b, b_g, b_a].
  SpeedBiasPriorFactor(const Vector9d& speed_bias_prior, const Matrix9d& sqrt_information);

  static ceres::CostFunction* Create(const Vector9d& speed_bias_prior,
                                     const Matrix9d& sqrt_information);
  /// Isotropic per part: velocity [m/s], gyro bias [rad/s], accel bias
  /// [m/s^2] sigmas (all > 0).
  static ceres::CostFunction* Create(const Vector9d& speed_bias_prior, double sigma_velocity_m_s,
                                     double sigma_gyro_bias_rad_s, double sigma_accel_bias_m_s2);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  Vector9d speed_bias_prior_;
  Matrix9d sqrt_information_;
};

}  // namespace vio
