#include "vio/estimator/anchored_point_factor.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "vio/estimator/pose_manifold.h"
#include "vio/estimator/so3.h"

namespace vio {

void AnchoredPointSummary::Add(const Eigen::Vector3d& p_b0, const Eigen::Vector3d& e0, const Eigen::Matrix3d& J) {
  const Eigen::Matrix3d H = J.transpose() * J;
  information_ += H;
  // The mean this residual alone gives: p_b0 - H^-1 J^T e0, weighted by H.
  information_mean_ += H * p_b0 - J.transpose() * e0;
  ++count_;
}

void AnchoredPointSummary::Absorb(const AnchoredPointSummary& other, const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  // Each of its residuals e(p_o) = e(R^T (p - t)): Jacobian J R^T, information R H R^T.
  const Eigen::Matrix3d H = R * other.information_ * R.transpose();
  information_ += H;
  information_mean_ += R * other.information_mean_ + H * t;
  count_ += other.count_;
}

bool AnchoredPointSummary::Usable() const {
  const Eigen::LLT<Eigen::Matrix3d> llt(information_);
  return count_ > 0 && llt.info() == Eigen::Success && information_.allFinite();
}

Eigen::Vector3d AnchoredPointSummary::mean() const { return information_.llt().solve(information_mean_); }

Eigen::Matrix3d AnchoredPointSummary::SqrtInformation() const {
  return (information_ / static_cast<double>(count_)).llt().matrixU();
}

bool AnchoredPointFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  return EvaluateImpl(parameters, residuals, jacobians, /*on_tangents=*/false);
}

bool AnchoredPointFactor::EvaluateOnTangents(double const* const* parameters, double* residuals,
                                             double** jacobians) const {
  return EvaluateImpl(parameters, residuals, jacobians, /*on_tangents=*/true);
}

bool AnchoredPointFactor::EvaluateImpl(double const* const* parameters, double* residuals, double** jacobians,
                                       bool on_tangents) const {
  const Eigen::Map<const Eigen::Vector3d> p_w_b(parameters[0]);
  const Eigen::Quaterniond q_w_b = Eigen::Map<const Eigen::Quaterniond>(parameters[0] + 3).normalized();
  const Eigen::Map<const Eigen::Vector3d> p_w_l(parameters[1]);
  const Eigen::Matrix3d R_b_w = q_w_b.toRotationMatrix().transpose();
  const Eigen::Vector3d p_b = R_b_w * (p_w_l - p_w_b);
  Eigen::Map<Eigen::Vector3d>{residuals} = sqrt_information_ * (p_b - p_b_hat_);
  if (jacobians == nullptr) return true;
  const Eigen::Matrix3d L_R_b_w = sqrt_information_ * R_b_w;
  if (jacobians[0] != nullptr) {
    Eigen::Matrix<double, 3, 6> J_tangent;
    J_tangent.leftCols<3>() = -L_R_b_w;
    J_tangent.rightCols<3>() = sqrt_information_ * so3::Hat(p_b);
    if (on_tangents) {
      Eigen::Map<Eigen::Matrix<double, 3, 6, Eigen::RowMajor>>{jacobians[0]} = J_tangent;
    } else {
      PoseJacobianToAmbient<3>(J_tangent, q_w_b, jacobians[0]);
    }
  }
  if (jacobians[1] != nullptr) Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>{jacobians[1]} = L_R_b_w;
  return true;
}

}  // namespace vio
