#include "vio/estimator/so3.h"

#include <cmath>

namespace vio::so3 {
namespace {

// Below this angle [rad] the closed forms lose precision to cancellation and
// their Taylor expansions are used instead (truncation error < 1e-13).
constexpr double kSmallAngle = 1e-4;

}  // namespace

Eigen::Matrix3d Hat(const Eigen::Vector3d& w) {
  Eigen::Matrix3d W;
  W << 0.0, -w.z(), w.y(),
       w.z(), 0.0, -w.x(),
       -w.y(), w.x(), 0.0;
  return W;
}

Eigen::Quaterniond ExpQuaternion(const Eigen::Vector3d& theta) {
  const double angle = theta.norm();
  // sin(a / 2) / a, the scale of the vector part.
  const double vector_scale =
      angle < kSmallAngle ? 0.5 - angle * angle / 48.0 : std::sin(0.5 * angle) / angle;
  const Eigen::Vector3d v = vector_scale * theta;
  return Eigen::Quaterniond(std::cos(0.5 * angle), v.x(), v.y(), v.z());
}

Eigen::Matrix3d Exp(const Eigen::Vector3d& theta) { return ExpQuaternion(theta).toRotationMatrix(); }

Eigen::Vector3d Log(const Eigen::Quaterniond& q) {
  // Work on the representative with w >= 0 so that the angle is <= pi.
  const double sign = q.w() < 0.0 ? -1.0 : 1.0;
  const double w = sign * q.w();
  const Eigen::Vector3d v = sign * q.vec();
  const double v_norm = v.norm();
  if (v_norm < kSmallAngle * 1e-2) {
    // 2 atan(n / w) / n ~= 2 / w * (1 - n^2 / (3 w^2)).
    return (2.0 / w) * (1.0 - v_norm * v_norm / (3.0 * w * w)) * v;
  }
  return (2.0 * std::atan2(v_norm, w) / v_norm) * v;
}

Eigen::Vector3d Log(const Eigen::Matrix3d& R) { return Log(Eigen::Quaterniond(R)); }

Eigen::Matrix3d RightJacobian(const Eigen::Vector3d& theta) {
  const double a = theta.norm();
  const Eigen::Matrix3d W = Hat(theta);
  double c1 = 0.0;  // (1 - cos a) / a^2
  double c2 = 0.0;  // (a - sin a) / a^3
  if (a < kSmallAngle) {
    c1 = 0.5 - a * a / 24.0;
    c2 = 1.0 / 6.0 - a * a / 120.0;
  } else {
    const double sin_half = std::sin(0.5 * a);
    c1 = 2.0 * sin_half * sin_half / (a * a);
    c2 = (a - std::sin(a)) / (a * a * a);
  }
  return Eigen::Matrix3d::Identity() - c1 * W + c2 * W * W;
}

Eigen::Matrix3d RightJacobianInverse(const Eigen::Vector3d& theta) {
  const double a = theta.norm();
  const Eigen::Matrix3d W = Hat(theta);
  // 1 / a^2 - cot(a / 2) / (2 a)
  const double c = a < kSmallAngle ? 1.0 / 12.0 + a * a / 720.0
                                   : 1.0 / (a * a) - 1.0 / (2.0 * a * std::tan(0.5 * a));
  return Eigen::Matrix3d::Identity() + 0.5 * W + c * W * W;
}

}  // namespace vio::so3
