#pragma once
// The equivalence theorems of the design paper (§4.3, appendix 6.2) in code:
// each filter sub-block of kalman_reference.h equals ONE Gauss-Newton step
// (Theorem 2.2.1, Algorithm 1) or ONE marginalization step (Theorem 2.2.2,
// Algorithm 2) on a cost built from the same linearized models:
//
//   Theorem 4.3.1  EKF feature augmentation (Alg. 6) = GN step on
//       c_EKF,t,1(x̃_t, f_new) = ||x̃_t ⊟ μ_t||²_Σt^-1 + Σ_k ||z_k - h(x_t, f_k)||²_Σv^-1
//       at (μ_t, ℓ̃(μ_x, z));
//   Theorem 4.3.2  EKF feature update (Alg. 7) = GN step on
//       c_EKF,t,3(x̃_t) = ||x̃_t ⊟ μ_t||²_Σt^-1 + Σ_k ||z_k - h(x_t, f_k)||²_Σv^-1 at μ_t;
//   Theorem 4.3.3  EKF propagation (Alg. 8) = marginalizing x_t out of
//       c_EKF,t,5(x̃_t, x_{t+1}) = ||x̃_t ⊟ μ̄_t||²_Σ̄t^-1 + ||x_{t+1} ⊟ g(x_t)||²_Σw^-1
//       at (μ̄_t, g(μ̄_x));
//   Theorem 4.3.4  MSCKF feature update (Alg. 11) = marginalizing f_{S_f} out of
//       c_MSCKF,t,3(x̃_t, f) = ||x̃_t ⊟ μ_t||²_Σt^-1 + Σ_(i,j) ||z_ij ⊟ h(x_i, f_j)||²_Σv^-1
//       at (μ_t, f*);
//   Theorem 4.3.5  MSCKF propagation (Alg. 12) = marginalizing x_t,IMU out of
//       c_MSCKF,t,5, the same form as c_EKF,t,5 with the poses for features;
//   Remark 4.3.2   MSCKF pose augmentation + propagation (Alg. 10 then 12) =
//       marginalizing only the non-pose part of x_t,IMU out of c_MSCKF,t,5: the
//       clone x_{n+1} is the pose part that is kept.
//
// A cost is a list of terms ||r(ξ)||²_Σ^-1, each linearized at ξ*:
// r(ξ* ⊞ δ) ≈ r + J δ. Whitening (eq. 2.1) stacks C = Σ^-1/2 r and
// J_C = Σ^-1/2 J (Σ^-1/2 = L^-1 for Σ = L L^T). The steps reuse
// linear_algebra.h: the marginalization step is SchurComplement (one block)
// or SchurComplementOfUncoupledBlocks (features).
#include <Eigen/Core>
#include <string>
#include <vector>

#include "vio/marginalization/gaussian_state.h"
#include "vio/marginalization/kalman_reference.h"

namespace vio::marginalization {

// ---------------------------------------------------------------------------
// The two steps of the optimization framework.

/// One term ||r(ξ)||²_Σ^-1 of a cost, linearized at ξ*: r(ξ* ⊞ δ) ≈ r + J δ,
/// J over the whole tangent of the cost's variables.
struct ResidualTerm {
  Eigen::VectorXd r;
  Eigen::MatrixXd J;
  Eigen::MatrixXd Sigma;  ///< positive definite, r.size() square
};

/// The whitened, stacked cost vector C(ξ* ⊞ δ) ≈ C + J δ (paper eq. 2.1).
struct LinearizedCost {
  Eigen::MatrixXd J;
  Eigen::VectorXd C;
};

/// Stacks Σ^-1/2 r and Σ^-1/2 J of every term. Throws std::invalid_argument
/// on inconsistent sizes or a covariance that is not positive definite.
LinearizedCost Whiten(const std::vector<ResidualTerm>& terms);

/// Algorithm 1 (Theorem 2.2.1): Σ = (J^T J)^-1, μ = ξ* ⊞ (-(J^T J)^-1 J^T C).
Gaussian GaussNewtonStep(const LinearizedCost& cost, const Eigen::VectorXd& linearization_point,
                         const StateLayout& layout);

/// Algorithm 2 (Theorem 2.2.2): the cost's variables are ordered kept first,
/// then the marginalized blocks of tangent sizes `marginalized_block_dims`.
/// With H = J^T J, b = J^T C and (H*, b*) their Schur complement (which equals
/// J_K^T [I - J_M (J_M^T J_M)^-1 J_M^T] (J_K, C)):
///   Σ_K = H*^-1,   μ_K = ξ_K* ⊞ (-Σ_K b*).
/// Several blocks must be mutually uncoupled (no term touches two of them).
Gaussian MarginalizationStep(const LinearizedCost& cost, const Eigen::VectorXd& kept_linearization_point,
                             const StateLayout& kept_layout, const std::vector<int>& marginalized_block_dims);

// ---------------------------------------------------------------------------
// The problems: one filter step's inputs, linearized once for both forms.

/// Theorem 4.3.1. The new features' linearization point is ℓ̃(μ_x, z).
struct EkfAugmentationProblem {
  StateLayout layout;                 ///< x̃_t = (x_t, f_1..f_p), robot blocks first
  int robot_dim = 0;                  ///< d_x: tangent size of x_t
  Gaussian state;                     ///< (μ_t, Σ_t)
  StateLayout new_feature_layout;     ///< f_{p+1..p+p'}
  Eigen::VectorXd new_feature_means;  ///< ℓ̃(μ_x, z)
  Eigen::MatrixXd L_x;                ///< ∂ℓ̃/∂x at (μ_x, z), p'd_f x d_x
  Eigen::MatrixXd L_z;                ///< ∂ℓ̃/∂z at (μ_x, z), p'd_f x p'd_z
  /// h̃(x_t, f_new) at (μ_x, ℓ̃): H_x over x_t (d_x columns), H_f over f_new.
  LinearizedMeasurements measurements;
};

/// Theorem 4.3.2: measurements of existing features, linearized at μ_t.
struct EkfUpdateProblem {
  StateLayout layout;
  Gaussian state;
  LinearizedMeasurements measurements;  ///< H_x over the whole x̃_t; no H_f
};

/// The dynamics term of c_5 linearized at (x_t*, x_{t+1}*) = (μ̄_x, g(μ̄_x)):
/// r = x_{t+1} ⊟ g(x_t) ≈ r0 + J_from δ_t + J_to δ_{t+1}.
struct DynamicsResidual {
  Eigen::VectorXd r0;      ///< x_{t+1}* ⊟ g(x_t*) (zero up to round-off)
  Eigen::MatrixXd J_from;  ///< ∂r/∂x_t (= -G)
  Eigen::MatrixXd J_to;    ///< ∂r/∂x_{t+1} (= I)
};

/// Theorems 4.3.3 / 4.3.5 and Remark 4.3.2 (Alg. 10 + 12).
struct PropagationProblem {
  StateLayout layout;    ///< (x_t, rest): the robot / IMU blocks first
  int robot_blocks = 1;  ///< how many leading blocks of `layout` form x_t
  /// Remark 4.3.2 only: how many leading blocks of x_t the MSCKF clones (the
  /// pose); fewer than robot_blocks.
  int cloned_blocks = 0;
  Gaussian state;               ///< (μ̄_t, Σ̄_t)
  LinearizedDynamics dynamics;  ///< filter form: g(μ̄_x), G, Σ_w
  DynamicsResidual residual;    ///< optimization form (noise Σ_w shared)
};

/// Theorem 4.3.4: measurements of the features S_f from the poses.
struct MsckfUpdateProblem {
  StateLayout layout;  ///< x̃_t = (x_IMU, x_1..x_n)
  Gaussian state;
  StateLayout feature_layout;         ///< f_{S_f}: one Euclidean block per feature
  Eigen::VectorXd feature_estimates;  ///< f*_{S_f} (e.g. triangulated)
  /// At (μ_t, f*): H_x over x̃_t, H_f over f_{S_f} (full column rank).
  LinearizedMeasurements measurements;
};

/// One of each, generated together (see RandomLinearGaussianProblems and the
/// nonlinear generator of vio_verify).
struct EquivalenceProblems {
  EkfAugmentationProblem ekf_augmentation;
  EkfUpdateProblem ekf_update;
  PropagationProblem ekf_propagation;
  MsckfUpdateProblem msckf_update;
  PropagationProblem msckf_propagation;  ///< cloned_blocks > 0: also Remark 4.3.2
};

// ---------------------------------------------------------------------------
// The optimization forms.

/// Theorem 4.3.1: one GN step on c_EKF,t,1 about (μ_t, ℓ̃(μ_x, z)).
Gaussian EkfAugmentationByGaussNewton(const EkfAugmentationProblem& problem);
/// Theorem 4.3.2: one GN step on c_EKF,t,3 about μ_t.
Gaussian EkfUpdateByGaussNewton(const EkfUpdateProblem& problem);
/// Theorems 4.3.3 / 4.3.5: one marginalization step on c_5 removing x_t; with
/// `keep_clone`, Remark 4.3.2: removing only x_t's blocks after the cloned
/// ones, which stay (last) as the new pose x_{n+1}.
Gaussian PropagationByMarginalization(const PropagationProblem& problem, bool keep_clone = false);
/// Theorem 4.3.4: one marginalization step on c_MSCKF,t,3 removing f_{S_f}.
Gaussian MsckfFeatureUpdateByMarginalization(const MsckfUpdateProblem& problem);

// ---------------------------------------------------------------------------
// The checks.

/// Both forms of one filter step and how far apart they are.
struct EquivalenceCheck {
  std::string theorem;      ///< "4.3.1" ... "4.3.5", "R4.3.2" (Remark 4.3.2)
  std::string description;  ///< e.g. "EKF feature augmentation (Alg. 6) = GN step on c_EKF,t,1"
  Gaussian filter;          ///< the reference filter (kalman_reference.h)
  Gaussian optimization;    ///< the optimization form
  Deviation deviation;      ///< of `optimization` from `filter`
};

EquivalenceCheck CheckEkfAugmentation(const EkfAugmentationProblem& problem);    ///< 4.3.1
EquivalenceCheck CheckEkfUpdate(const EkfUpdateProblem& problem);                ///< 4.3.2
EquivalenceCheck CheckEkfPropagation(const PropagationProblem& problem);         ///< 4.3.3
EquivalenceCheck CheckMsckfFeatureUpdate(const MsckfUpdateProblem& problem);     ///< 4.3.4
EquivalenceCheck CheckMsckfPropagation(const PropagationProblem& problem);       ///< 4.3.5
EquivalenceCheck CheckMsckfPoseAugmentation(const PropagationProblem& problem);  ///< Remark 4.3.2

/// Every check above on `problems`, in theorem order (the pose augmentation
/// last, when problems.msckf_propagation.cloned_blocks > 0).
std::vector<EquivalenceCheck> CheckAll(const EquivalenceProblems& problems);

/// Negative controls: deliberately wrong filter variants that must NOT agree
/// with the optimization form (so the checks can fail). Same fields as a
/// check; `deviation` is expected to be large.
///   "4.3.4 without null-space projection": the MSCKF update treating f* as
///       known (an EKF update with H_x alone);
///   "4.3.2 with H perturbed by 1e-5": the EKF update with a Jacobian off by
///       1e-5 relative.
std::vector<EquivalenceCheck> NegativeControls(const EquivalenceProblems& problems);

// ---------------------------------------------------------------------------
// Random linear-Gaussian problems: h(x, f) = H_x x + H_f f, g(x) = G x + u,
// all blocks Euclidean, random Jacobians, random correlated covariances.

struct LinearProblemSizes {
  int robot_dim = 6;         ///< d_x: EKF robot state, MSCKF pose
  int imu_dim = 9;           ///< d_IMU (> d_x): its first d_x entries are the cloned pose
  int feature_dim = 3;       ///< d_f = d_z (the EKF's inverse measurement map needs it)
  int num_features = 4;      ///< p (EKF) and |S_f| (MSCKF)
  int num_new_features = 2;  ///< p'
  int num_poses = 4;         ///< n (MSCKF), >= 2: each feature is seen from 2..n poses
};

/// Throws std::invalid_argument on sizes outside the documented ranges.
EquivalenceProblems RandomLinearGaussianProblems(const LinearProblemSizes& sizes, unsigned seed);

}  // namespace vio::marginalization
