#include "vio/estimator/pose_manifold.h"

#include "vio/estimator/so3.h"

namespace vio {
namespace {

using RowMajorMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

Eigen::Map<const Eigen::Vector3d> Position(const double* pose) {
  return Eigen::Map<const Eigen::Vector3d>(pose);
}

Eigen::Map<const Eigen::Quaterniond> Rotation(const double* pose) {
  return Eigen::Map<const Eigen::Quaterniond>(pose + 3);
}

}  // namespace

Eigen::Matrix<double, 4, 3> QuaternionPlusJacobian(const Eigen::Quaterniond& q) {
  Eigen::Matrix<double, 4, 3> J;
  J.topRows<3>() = 0.5 * (q.w() * Eigen::Matrix3d::Identity() + so3::Hat(q.vec()));
  J.bottomRows<1>() = -0.5 * q.vec().transpose();
  return J;
}

Eigen::Matrix<double, 3, 4> QuaternionMinusJacobian(const Eigen::Quaterniond& q) {
  Eigen::Matrix<double, 3, 4> J;
  J.leftCols<3>() = 2.0 * (q.w() * Eigen::Matrix3d::Identity() - so3::Hat(q.vec()));
  J.rightCols<1>() = -2.0 * q.vec();
  return J;
}

bool PoseManifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  const Eigen::Map<const Eigen::Vector3d> dp(delta);
  const Eigen::Map<const Eigen::Vector3d> dtheta(delta + 3);
  Eigen::Map<Eigen::Vector3d>{x_plus_delta} = Position(x) + dp;
  Eigen::Map<Eigen::Quaterniond>(x_plus_delta + 3) =
      (Rotation(x) * so3::ExpQuaternion(dtheta)).normalized();
  return true;
}

bool PoseManifold::PlusJacobian(const double* x, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, kPoseSize, kPoseTangentSize, Eigen::RowMajor>> J(jacobian);
  J.setZero();
  J.topLeftCorner<3, 3>().setIdentity();
  J.bottomRightCorner<4, 3>() = QuaternionPlusJacobian(Rotation(x));
  return true;
}

bool PoseManifold::RightMultiplyByPlusJacobian(const double* x, int num_rows,
                                               const double* ambient_matrix,
                                               double* tangent_matrix) const {
  const Eigen::Map<const RowMajorMatrixXd> A(ambient_matrix, num_rows, kPoseSize);
  Eigen::Map<RowMajorMatrixXd> T(tangent_matrix, num_rows, kPoseTangentSize);
  T.leftCols<3>() = A.leftCols<3>();
  T.rightCols<3>() = A.rightCols<4>() * QuaternionPlusJacobian(Rotation(x));
  return true;
}

bool PoseManifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  Eigen::Map<Eigen::Vector3d>{y_minus_x} = Position(y) - Position(x);
  Eigen::Map<Eigen::Vector3d>(y_minus_x + 3) = so3::Log(Rotation(x).conjugate() * Rotation(y));
  return true;
}

bool PoseManifold::MinusJacobian(const double* x, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, kPoseTangentSize, kPoseSize, Eigen::RowMajor>> J(jacobian);
  J.setZero();
  J.topLeftCorner<3, 3>().setIdentity();
  J.bottomRightCorner<3, 4>() = QuaternionMinusJacobian(Rotation(x));
  return true;
}

bool PoseManifold::MinusTangentJacobian(const double* x, const double* x0, double* jacobian) const {
  Eigen::Map<Eigen::Matrix<double, kPoseTangentSize, kPoseTangentSize, Eigen::RowMajor>> J(jacobian);
  J.setIdentity();
  J.bottomRightCorner<3, 3>() =
      so3::RightJacobianInverse(so3::Log(Rotation(x0).conjugate() * Rotation(x)));
  return true;
}

}  // namespace vio
