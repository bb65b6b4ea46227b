#pragma once
// IMU factor between two consecutive states i and j (Forster et al. 2017).
//
// Parameter blocks: pose_i [p_w_bi, q_w_bi] (7), speed_bias_i [v_i, bg_i,
// ba_i] (9), pose_j (7), speed_bias_j (9). With dt the preintegrated time,
// (dR, dv, dp) the preintegrated deltas bias-corrected to first order at
// (bg_i, ba_i) and R_i = R(q_w_bi), the residual (order = preintegration error
// state) is
//   r_R  = Log(dR^T R_i^T R_j)
//   r_v  = R_i^T (v_j - v_i - g_w dt) - dv
//   r_p  = R_i^T (p_j - p_i - v_i dt - 1/2 g_w dt^2) - dp
//   r_bg = bg_j - bg_i
//   r_ba = ba_j - ba_i
// whitened by S (S^T S = Sigma^-1 of the preintegration): e = S r.
//
// Tangent Jacobians (pose tangent [dp, dtheta], q <- q Exp(dtheta)),
// with Jr^-1 = RightJacobianInverse(r_R), E = dR^T R_i^T R_j,
// phi_b = dR/dbg (bg_i - bg_lin):
//   d r_R / d theta_i = -Jr^-1 R_j^T R_i      d r_R / d theta_j = Jr^-1
//   d r_R / d bg_i    = -Jr^-1 E^T Jr(phi_b) dR/dbg
//   d r_v / d theta_i = [R_i^T (v_j - v_i - g dt)]x
//   d r_v / d v_i = -R_i^T,  d r_v / d v_j = R_i^T,
//   d r_v / d bg_i = -dv/dbg, d r_v / d ba_i = -dv/dba
//   d r_p / d theta_i = [R_i^T (p_j - p_i - v_i dt - 1/2 g dt^2)]x
//   d r_p / d p_i = -R_i^T, d r_p / d p_j = R_i^T, d r_p / d v_i = -R_i^T dt,
//   d r_p / d bg_i = -dp/dbg, d r_p / d ba_i = -dp/dba
//   d r_b / d b_i = -I, d r_b / d b_j = I
// Pose Jacobians are written in ambient form (see pose_manifold.h).
//
// The factor keeps a copy of the preintegration and its whitening taken at
// construction: after ImuPreintegration::Reintegrate, build a new factor.
#include <ceres/sized_cost_function.h>

#include <Eigen/Core>

#include "vio/estimator/imu_preintegration.h"
#include "vio/marginalization/tangent_cost_function.h"

namespace vio {

class ImuFactor final : public ceres::SizedCostFunction<15, 7, 9, 7, 9>, public marginalization::TangentCostFunction {
 public:
  using Vector15d = Eigen::Matrix<double, 15, 1>;

  /// `preintegration` must hold at least one step; g_w is the gravity vector
  /// in world [m/s^2].
  explicit ImuFactor(const ImuPreintegration& preintegration,
                     const Eigen::Vector3d& g_w = Eigen::Vector3d(0.0, 0.0, -9.81));

  static ceres::CostFunction* Create(const ImuPreintegration& preintegration,
                                     const Eigen::Vector3d& g_w = Eigen::Vector3d(0.0, 0.0, -9.81));

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;
  bool EvaluateOnTangents(double const* const* parameters, double* residuals,
                          double** jacobians) const override;

  /// The residual r before whitening (diagnostics).
  Vector15d UnwhitenedResidual(double const* const* parameters) const;

  const ImuPreintegration& preintegration() const { return preintegration_; }
  const ImuPreintegration::Matrix15d& sqrt_information() const { return sqrt_information_; }

 private:
  struct States;
  struct Linearization;

  Linearization Linearize(const States& states) const;
  bool EvaluateImpl(double const* const* parameters, double* residuals, double** jacobians, bool on_tangents) const;
  void WriteJacobians(const States& states, const Linearization& lin, double** jacobians, bool on_tangents) const;

  ImuPreintegration preintegration_;
  Eigen::Vector3d g_w_;
  ImuPreintegration::Matrix15d sqrt_information_;
};

}  // namespace vio
