#pragma once
// Prior on one pose block [p_w_b, q_w_b] (7).
//
//   r = [p_w_b - p0,  Log(q0^-1 q_w_b)],   e = S r   (S: 6x6 sqrt information)
// Tangent Jacobian (pose tangent [dp, dtheta], q <- q Exp(dtheta)):
//   d r / d[dp, dtheta] = blockdiag(I, Jr^-1(r_theta)),   d e = S d r,
// written in ambient form (see pose_manifold.h).
#include <ceres/sized_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace vio {

class PosePriorFactor final : public ceres::SizedCostFunction<6, 7> {
 public:
  using Matrix6d = Eigen::Matrix<double, 6, 6>;

  /// sqrt_information: S with S^T S = Sigma^-1 over [dp, dtheta].
  PosePriorFactor(const Eigen::Vector3d& p_w_b_prior, const Eigen::Quaterniond& q_w_b_prior,
                  const Matrix6d& sqrt_information);

  static ceres::CostFunction* Create(const Eigen::Vector3d& p_w_b_prior,
                                     const Eigen::Quaterniond& q_w_b_prior,
                                     const Matrix6d& sqrt_information);
  /// Isotropic prior: position sigma [m], rotation sigma [rad] (both > 0).
  static ceres::CostFunction* Create(const Eigen::Vector3d& p_w_b_prior,
                                     const Eigen::Quaterniond& q_w_b_prior,
                                     double sigma_position_m, double sigma_rotation_rad);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  Eigen::Vector3d p_w_b_prior_;
  Eigen::Quaterniond q_w_b_prior_;
  Matrix6d sqrt_information_;
};

}  // namespace vio
