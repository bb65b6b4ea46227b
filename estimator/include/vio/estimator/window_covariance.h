#pragma once
// Marginal covariances from the window's information (prior + every factor)
// at the current estimate.
//
// The information is the Gauss-Newton system of the window's own assembly
// (gauss_newton.h: the same linearization as a step, robust losses applied
// as Ceres applies them): landmarks not tied by a prior are eliminated block
// by block (Schur complement), which leaves H over the states (and the
// landmarks a prior ties), a few hundred dimensions at most. The marginal
// covariance of some blocks is the matching block of H^-1, found by one
// Cholesky factorization and a solve for their columns only.
//
// Convention (pose_manifold.h): covariances are over the tangent spaces
// x ⊞ d, so the pose block's 6x6 is over [dp (3, world frame, m), dtheta (3,
// body frame, rad)] with p = p_hat + dp and q = q_hat * Exp(dtheta): the error
// of an estimate x_hat against the truth x is x ⊟ x_hat = [p - p_hat,
// Log(q_hat^-1 q)].
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <ceres/problem.h>

#include "vio/estimator/gauss_newton.h"
#include "vio/estimator/types.h"

namespace vio {

class Window;

/// Tangent size of one state: pose (6) + speed and biases (9).
inline constexpr int kStateTangentSize = 15;

/// The marginal covariance of one state.
struct StateCovariance {
  StateId id;
  Timestamp t_ns = 0;
  /// Over [dp (world, m), dtheta (body, rad), v_w_b (m/s), b_g (rad/s), b_a (m/s^2)].
  Eigen::Matrix<double, kStateTangentSize, kStateTangentSize> covariance;
};

/// The marginal covariance of `blocks` (each one of layout.dense), stacked in
/// the given order over their tangent spaces; nothing when the information
/// is singular (a direction no factor or prior constrains) or evaluation fails.
std::optional<Eigen::MatrixXd> MarginalCovariance(ceres::Problem* problem, const GaussNewtonLayout& layout,
                                                  const std::vector<const double*>& blocks);

/// The marginal covariance of the window's newest state at its current
/// estimate; nothing when the window is empty, the newest state is held
/// constant or the information is singular.
std::optional<StateCovariance> NewestStateCovariance(Window& window);

}  // namespace vio
