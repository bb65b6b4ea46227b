// EKF-SLAM sub-blocks of the design paper, appendix Algorithms 6-8.
#include <Eigen/Cholesky>

#include "equivalence_internal.h"
#include "vio/marginalization/kalman_reference.h"

namespace vio::marginalization {
namespace {

using internal::RequireGaussian;
using internal::Symmetrized;

}  // namespace

// Algorithm 6. Lines 1-4: μ ← (μ, ℓ̃(μ_x, z)); lines 5-9: the covariance of
// (x̃, ℓ̃(x, z)) to first order, with z independent of x̃.
Gaussian EkfAugmentFeatures(const Gaussian& state, int robot_dim, const Eigen::VectorXd& new_feature_means,
                            const Eigen::MatrixXd& L_x, const Eigen::MatrixXd& L_z,
                            const Eigen::MatrixXd& Sigma_v) {
  RequireGaussian(state);
  const Eigen::Index d = state.covariance.rows();  // d_x + p d_f
  const Eigen::Index new_dim = L_x.rows();         // p' d_f
  VIO_REQUIRE_INPUT(robot_dim >= 0 && robot_dim <= d);
  VIO_REQUIRE_SHAPE(L_x, new_dim, robot_dim);
  VIO_REQUIRE_SHAPE(L_z, new_dim, Sigma_v.rows());
  VIO_REQUIRE_SHAPE(Sigma_v, L_z.cols(), L_z.cols());

  const Eigen::MatrixXd& Sigma = state.covariance;
  const Eigen::MatrixXd Sigma_all_x = Sigma.leftCols(robot_dim);  // [Σ_xx; Σ_fx]
  Gaussian augmented;
  augmented.mean.resize(state.mean.size() + new_feature_means.size());
  augmented.mean << state.mean, new_feature_means;
  augmented.covariance.resize(d + new_dim, d + new_dim);
  augmented.covariance.topLeftCorner(d, d) = Sigma;
  augmented.covariance.topRightCorner(d, new_dim) = Sigma_all_x * L_x.transpose();
  augmented.covariance.bottomLeftCorner(new_dim, d) = L_x * Sigma_all_x.transpose();
  augmented.covariance.bottomRightCorner(new_dim, new_dim) =
      L_x * Sigma.topLeftCorner(robot_dim, robot_dim) * L_x.transpose() + L_z * Sigma_v * L_z.transpose();
  augmented.covariance = Symmetrized(augmented.covariance);
  return augmented;
}

// Algorithm 7, lines 5-6: the Kalman gain form.
Gaussian EkfUpdate(const Gaussian& state, const StateLayout& layout,
                   const LinearizedMeasurements& measurements) {
  RequireGaussian(state);
  const Eigen::Index d = layout.TangentSize();
  const Eigen::Index m = measurements.innovation.size();
  VIO_REQUIRE_SHAPE(state.covariance, d, d);
  VIO_REQUIRE_SHAPE(measurements.H_x, m, d);
  VIO_REQUIRE_SHAPE(measurements.Sigma_v, m, m);
  VIO_REQUIRE_INPUT(measurements.H_f.size() == 0);
  if (m == 0) return state;

  const Eigen::MatrixXd& Sigma = state.covariance;
  const Eigen::MatrixXd& H = measurements.H_x;
  const Eigen::MatrixXd Sigma_Ht = Sigma * H.transpose();
  const Eigen::LLT<Eigen::MatrixXd> S(Symmetrized(H * Sigma_Ht + measurements.Sigma_v));
  VIO_REQUIRE_INPUT(S.info() == Eigen::Success);                        // H Σ H^T + Σ_v positive definite
  const Eigen::MatrixXd K = S.solve(Sigma_Ht.transpose()).transpose();  // Σ H^T S^-1
  Gaussian updated;
  updated.mean = layout.Plus(state.mean, K * measurements.innovation);
  updated.covariance = Symmetrized(Sigma - K * Sigma_Ht.transpose());  // Σ - K H Σ
  return updated;
}

// Algorithm 8, lines 3-5.
Gaussian EkfPropagate(const Gaussian& state, const LinearizedDynamics& dynamics) {
  RequireGaussian(state);
  const Eigen::Index d = state.covariance.rows();
  const Eigen::Index d_x = dynamics.G.rows();
  const Eigen::Index d_f = d - d_x;  // p d_f
  const Eigen::Index ambient_x = dynamics.g_of_mean.size();
  VIO_REQUIRE_INPUT(d_x <= d && ambient_x <= state.mean.size());
  VIO_REQUIRE_SHAPE(dynamics.G, d_x, d_x);
  VIO_REQUIRE_SHAPE(dynamics.Sigma_w, d_x, d_x);

  const Eigen::MatrixXd& G = dynamics.G;
  const Eigen::MatrixXd& Sigma = state.covariance;
  Gaussian propagated;
  propagated.mean = state.mean;
  propagated.mean.head(ambient_x) = dynamics.g_of_mean;
  propagated.covariance.resize(d, d);
  propagated.covariance.topLeftCorner(d_x, d_x) =
      G * Sigma.topLeftCorner(d_x, d_x) * G.transpose() + dynamics.Sigma_w;
  propagated.covariance.topRightCorner(d_x, d_f) = G * Sigma.topRightCorner(d_x, d_f);
  propagated.covariance.bottomLeftCorner(d_f, d_x) = Sigma.bottomLeftCorner(d_f, d_x) * G.transpose();
  propagated.covariance.bottomRightCorner(d_f, d_f) = Sigma.bottomRightCorner(d_f, d_f);
  propagated.covariance = Symmetrized(propagated.covariance);
  return propagated;
}

}  // namespace vio::marginalization
