#pragma once
// Reference covariance-form filters of the design paper (appendix 6.1): the
// EKF-SLAM sub-blocks (Algorithms 6-8) and the MSCKF sub-blocks (Algorithms
// 10-12), written in the paper's notation. They exist to VERIFY the paper's
// equivalence theorems (4.3.1-4.3.5, see equivalence.h), not to run a filter.
//
// Each function maps a Gaussian (μ_t, Σ_t) over a stacked state and the
// models linearized at the current estimate (Jacobians, residuals, noise
// covariances) to the new Gaussian. Jacobians are taken with respect to the
// tangent spaces of the state blocks (x ⊞ δ), so the same code serves a
// Euclidean state and one with pose blocks. Bad input (inconsistent shapes, a
// noise covariance that is not positive definite, unobservable features)
// throws std::invalid_argument naming the file, line and condition.
#include <Eigen/Core>

#include "vio/marginalization/gaussian_state.h"

namespace vio::marginalization {

/// Measurements z̃ = h̃(ξ) + v, v ~ N(0, Σ̃_v), linearized at ξ* = (x̃*, f*):
///   z̃ ⊟ h̃(x̃* ⊞ δ_x, f* + δ_f) ≈ innovation - H_x δ_x - H_f δ_f.
/// Which variables H_x covers is stated by each function.
struct LinearizedMeasurements {
  Eigen::VectorXd innovation;  ///< z̃ - h̃(ξ*), m
  Eigen::MatrixXd H_x;         ///< ∂h̃/∂x (state part), m x d
  Eigen::MatrixXd H_f;         ///< ∂h̃/∂f (feature part), m x k; empty when h̃ has none
  Eigen::MatrixXd Sigma_v;     ///< Σ̃_v = diag(Σ_v, ..., Σ_v), m x m, positive definite
};

/// Dynamics x_{t+1} = g(x_t) + w, w ~ N(0, Σ_w), linearized at μ_x:
///   g(μ_x ⊞ δ) ≈ g(μ_x) ⊞ (G δ).
struct LinearizedDynamics {
  Eigen::VectorXd g_of_mean;  ///< g(μ_x), ambient parameters of x_{t+1}
  Eigen::MatrixXd G;          ///< ∂g/∂x at μ_x, d_x x d_x
  Eigen::MatrixXd Sigma_w;    ///< Σ_w, d_x x d_x, positive definite
};

/// Algorithm 6, EKF feature augmentation. The state is x̃_t = (x_t, f_1..f_p)
/// with the robot x_t in its first `robot_dim` tangent dimensions. The p' new
/// features get the means ℓ̃(μ_x, z) (`new_feature_means`, ambient) from the
/// inverse measurement map ℓ, with L_x = ∂ℓ̃/∂x (p'd_f x d_x), L_z = ∂ℓ̃/∂z
/// (p'd_f x p'd_z) and the stacked noise Σ̃_v (p'd_z x p'd_z):
///   μ ← (μ, ℓ̃),
///   Σ ← [ Σ_xx      Σ_xf      Σ_xx L_x^T                   ]
///       [ Σ_fx      Σ_ff      Σ_fx L_x^T                   ]
///       [ L_x Σ_xx  L_x Σ_xf  L_x Σ_xx L_x^T + L_z Σ̃_v L_z^T ].
Gaussian EkfAugmentFeatures(const Gaussian& state, int robot_dim, const Eigen::VectorXd& new_feature_means,
                            const Eigen::MatrixXd& L_x, const Eigen::MatrixXd& L_z,
                            const Eigen::MatrixXd& Sigma_v);

/// Algorithm 7, EKF feature update, with H_t = measurements.H_x over the whole
/// state x̃_t (measurements.H_f must be empty):
///   K = Σ H_t^T (H_t Σ H_t^T + Σ̃_v)^-1,
///   μ̄ = μ ⊞ K (z̃ - h̃(μ)),     Σ̄ = Σ - K H_t Σ.
Gaussian EkfUpdate(const Gaussian& state, const StateLayout& layout,
                   const LinearizedMeasurements& measurements);

/// Algorithm 8, EKF state propagation. The robot x_t is the first
/// dynamics.G.rows() tangent dimensions and the first
/// dynamics.g_of_mean.size() mean entries; the features are static:
///   μ_{t+1} = (g(μ̄_x), μ̄_f),
///   Σ_{t+1} = [ G Σ̄_xx G^T + Σ_w   G Σ̄_xf ]
///             [ Σ̄_fx G^T           Σ̄_ff   ].
Gaussian EkfPropagate(const Gaussian& state, const LinearizedDynamics& dynamics);

/// Algorithm 10, MSCKF pose augmentation: appends the new pose
/// x_{n+1} = ψ(x̃_t), with mean `new_pose_mean` = ψ(μ) (ambient) and
/// Psi = ∂ψ/∂x̃_t (d_x x dim(x̃_t)):
///   μ ← (μ, ψ(μ)),    Σ ← [I; Ψ] Σ [I; Ψ]^T   (rank-deficient by construction).
Gaussian MsckfAugmentPose(const Gaussian& state, const Eigen::VectorXd& new_pose_mean,
                          const Eigen::MatrixXd& Psi);

/// Algorithm 11, MSCKF feature update: the features f_{S_f} (estimates f*)
/// are removed from the measurements by the null-space projection, then the
/// system is compressed by QR and used in an EKF update. measurements.H_x is
/// over x̃_t, measurements.H_f over f_{S_f} (full column rank). Lines:
///   7-8  A: orthonormal basis of N(H̃_f^T)  (so A^T H̃_f = 0),
///   9    Q T = A^T H̃_x (QR),  r_n = Q^T A^T (z̃ - h̃(μ, f*)),  R_n = Q^T A^T Σ̃_v A Q,
///   10-11 the EKF update with (T, r_n, R_n). The paper writes it in
///        information form, Σ̄^-1 = Σ^-1 + T^T R_n^-1 T; this is the
///        covariance (gain) form, equal by the Woodbury identity.
/// When T has more rows than columns its lower rows are zero: they only
/// observe noise, so they are conditioned away (r1 - R12 R22^-1 r2 with noise
/// R11 - R12 R22^-1 R21), exact for any Σ̃_v; for Σ̃_v = σ² I, R12 = 0 and this
/// is the usual MSCKF compression that drops them.
Gaussian MsckfFeatureUpdate(const Gaussian& state, const StateLayout& layout,
                            const LinearizedMeasurements& measurements);

/// Algorithm 12, MSCKF state propagation of the IMU state x_{t,IMU} (the first
/// dynamics.G.rows() tangent dimensions) with the poses x_1..x_n static:
///   μ_{t+1} = (g_IMU(μ̄_IMU), μ̄_x,1:n),
///   Σ_{t+1} = Φ Σ̄ Φ^T + diag(Σ_w, O),   Φ = diag(G_t, I_{n d_x}).
/// (The paper's line 4 prints I_{n d_x} in the noise term; the poses get no
/// process noise, as its proof of Theorem 6.2.5 shows.)
Gaussian MsckfPropagate(const Gaussian& state, const LinearizedDynamics& dynamics);

}  // namespace vio::marginalization
