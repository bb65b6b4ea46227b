#pragma once
// Parameter-block layouts of the estimator and the manifold of the pose block.
//
// Pose block (7 doubles): [p_w_b (3), q_w_b (4: x y z w, Eigen order)], body =
// IMU. Tangent (6): [dp (3, world frame), dtheta (3, body frame)]:
//   Plus(x, d):  p' = p + dp,        q' = q * Exp(dtheta)    (q' normalized)
//   Minus(y, x): dp = p_y - p_x,     dtheta = Log(q_x^-1 * q_y)
// Log takes the shortest rotation, so Minus is insensitive to the sign of
// either quaternion (Plus(x, Minus(y, x)) equals y up to the sign of q_y).
//
// Jacobians at delta = 0 (q = [v, w], v the vector part):
//   d q' / d dtheta = Jq+ = 1/2 [ w I + Hat(v) ; -v^T ]          (4x3)
//   d dtheta / d q_y = Jq- = 2 [ w I - Hat(v) , -v ]    (at y = x, 3x4)
// Jq- * Jq+ = (w^2 + |v|^2) I = I, and Jq- = 4 Jq+^T is the pseudo-inverse of
// Jq+. The position parts are identities.
//
// Factor convention (every factor of this library): a factor computes its
// Jacobian J_tangent with respect to the tangent [dp, dtheta] and writes the
// ambient Jacobian J_ambient = [J_tangent_dp, J_tangent_dtheta * Jq-], so that
// J_ambient * PlusJacobian(x) == J_tangent exactly (see
// PoseJacobianToAmbient). Since the factors normalize q before use and
// Jq- q = 0, this is also the exact ambient derivative (zero along q).
//
// For marginalization priors the manifold also gives, for any x and x0,
//   d Minus(Plus(x, d), x0) / d d at d = 0 = blockdiag(I, Jr^-1(Log(q0^-1 q)))
// (vio::marginalization::LocalCoordinatesJacobian).
//
// Speed-and-bias block (9 doubles, Euclidean): [v_w_b (3), b_g (3), b_a (3)].
// Landmark block (3 doubles, Euclidean): p_w_l.
#include <ceres/manifold.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "vio/marginalization/local_coordinates_jacobian.h"

namespace vio {

inline constexpr int kPoseSize = 7;         ///< ambient size of a pose block
inline constexpr int kPoseTangentSize = 6;  ///< tangent size of a pose block
inline constexpr int kSpeedBiasSize = 9;    ///< [v_w_b, b_g, b_a]
inline constexpr int kLandmarkSize = 3;     ///< p_w_l

/// d(q * Exp(dtheta)) / d dtheta at dtheta = 0, rows in (x, y, z, w) order.
Eigen::Matrix<double, 4, 3> QuaternionPlusJacobian(const Eigen::Quaterniond& q);

/// d Log(q^-1 * y) / d y at y = q, columns in (x, y, z, w) order.
Eigen::Matrix<double, 3, 4> QuaternionMinusJacobian(const Eigen::Quaterniond& q);

/// Writes the row-major Ceres ambient Jacobian (kRows x 7) of a pose block
/// from the tangent-space Jacobian (kRows x 6, columns [dp, dtheta]) so that
/// ambient * PoseManifold::PlusJacobian == tangent.
template <int kRows>
void PoseJacobianToAmbient(const Eigen::Matrix<double, kRows, kPoseTangentSize>& J_tangent,
                           const Eigen::Quaterniond& q_w_b, double* jacobian_ambient) {
  Eigen::Map<Eigen::Matrix<double, kRows, kPoseSize, Eigen::RowMajor>> J(jacobian_ambient);
  J.template leftCols<3>() = J_tangent.template leftCols<3>();
  J.template rightCols<4>() = J_tangent.template rightCols<3>() * QuaternionMinusJacobian(q_w_b);
}

/// The manifold of the 7-double pose block (see the file comment).
class PoseManifold final : public ceres::Manifold,
                           public marginalization::LocalCoordinatesJacobian {
 public:
  int AmbientSize() const override { return kPoseSize; }
  int TangentSize() const override { return kPoseTangentSize; }

  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  /// 7x6 row-major.
  bool PlusJacobian(const double* x, double* jacobian) const override;
  /// ambient_matrix (num_rows x 7) * PlusJacobian(x), both row-major.
  bool RightMultiplyByPlusJacobian(const double* x, int num_rows, const double* ambient_matrix,
                                   double* tangent_matrix) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  /// 6x7 row-major.
  bool MinusJacobian(const double* x, double* jacobian) const override;
  /// d Minus(Plus(x, delta), x0) / d delta at delta = 0, 6x6 row-major.
  bool MinusTangentJacobian(const double* x, const double* x0, double* jacobian) const override;
};

}  // namespace vio
