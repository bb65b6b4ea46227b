#pragma once
// Small SO(3) helpers shared by the manifold, the IMU preintegration and the
// factors.
//
// Conventions: rotation vectors theta in R^3 (axis * angle, radians);
// Exp: R^3 -> SO(3), Log: SO(3) -> R^3 with |Log(R)| <= pi. Quaternions are
// Hamilton (Eigen). The right Jacobian Jr(theta) is defined by
//   Exp(theta + d) ~= Exp(theta) * Exp(Jr(theta) * d)       (d small),
// and its inverse by
//   Log(Exp(theta) * Exp(d)) ~= theta + Jr^-1(theta) * d.
// Closed forms (a = |theta|, W = Hat(theta)):
//   Jr    = I - (1 - cos a) / a^2 * W + (a - sin a) / a^3 * W^2
//   Jr^-1 = I + 1/2 * W + (1 / a^2 - cot(a / 2) / (2 a)) * W^2
// with Taylor expansions near a = 0.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace vio::so3 {

/// The skew-symmetric matrix with Hat(w) * v = w x v.
Eigen::Matrix3d Hat(const Eigen::Vector3d& w);

/// Unit quaternion of the rotation vector theta [rad].
Eigen::Quaterniond ExpQuaternion(const Eigen::Vector3d& theta);

/// Rotation matrix of the rotation vector theta [rad].
Eigen::Matrix3d Exp(const Eigen::Vector3d& theta);

/// Rotation vector of a unit quaternion; q and -q give the same result (the
/// shortest rotation, |result| <= pi).
Eigen::Vector3d Log(const Eigen::Quaterniond& q);

/// Rotation vector of a rotation matrix (|result| <= pi).
Eigen::Vector3d Log(const Eigen::Matrix3d& R);

/// Right Jacobian Jr(theta) of SO(3).
Eigen::Matrix3d RightJacobian(const Eigen::Vector3d& theta);

/// Inverse of the right Jacobian, Jr^-1(theta); valid for |theta| < 2 pi.
Eigen::Matrix3d RightJacobianInverse(const Eigen::Vector3d& theta);

}  // namespace vio::so3
