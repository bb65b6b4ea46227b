#include "vio/estimator/rig_rotation_search.h"

#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include "vio/estimator/so3.h"

namespace vio {
namespace {

// Past the decision's pair and rotation thresholds, the fit is tried every this many pairs.
constexpr int kFitEvery = 10;

// The rotation nearest A (its polar factor; a reflection's sign moved to the smallest singular value).
Eigen::Matrix3d Polar(const Eigen::Matrix3d& A) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixU() * d * svd.matrixV().transpose();
}

}  // namespace

void RigRotationSearch::AddPair(const Eigen::Vector3d& theta_gyro, const Eigen::Vector3d& theta_camera, double dt_s) {
  if (result_ || !(dt_s > 0) || !theta_gyro.allFinite() || !theta_camera.allFinite()) return;
  if (theta_camera.norm() < options_.min_pair_rotation_rad) return;
  pairs_.push_back({theta_gyro, theta_camera, dt_s});
  rotation_rad_ += theta_camera.norm();
  const int n = static_cast<int>(pairs_.size());
  if (n < options_.decision_pairs || rotation_rad_ < options_.decision_rotation_rad || n % kFitEvery != 0) return;
  Result fit = Fit();
  if (fit.sigma_rad < options_.decision_sigma_rad) {
    result_ = fit;
    pairs_.clear();
  }
}

const std::optional<RigRotationSearch::Result>& RigRotationSearch::Decide() {
  if (!result_ && static_cast<int>(pairs_.size()) >= options_.decision_pairs) {
    result_ = Fit();
    pairs_.clear();
  }
  return result_;
}

RigRotationSearch::Result RigRotationSearch::Fit() const {
  Result result;
  result.pairs = static_cast<int>(pairs_.size());
  result.rotation_rad = rotation_rad_;
  result.sigma_rad = std::numeric_limits<double>::infinity();
  if (pairs_.size() < 3) return result;
  // theta_gyro = A theta_camera + b dt, each row of (A, b) by linear least squares: the same
  // normal matrix over x = (theta_camera, dt) for all three.
  Eigen::Matrix4d normal = Eigen::Matrix4d::Zero();
  Eigen::Matrix<double, 4, 3> rhs = Eigen::Matrix<double, 4, 3>::Zero();
  for (const Pair& p : pairs_) {
    const Eigen::Vector4d x(p.theta_camera.x(), p.theta_camera.y(), p.theta_camera.z(), p.dt_s);
    normal += x * x.transpose();
    rhs += x * p.theta_gyro.transpose();
  }
  const Eigen::LDLT<Eigen::Matrix4d> ldlt(normal);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 0)) return result;
  const Eigen::Matrix<double, 4, 3> solution = ldlt.solve(rhs);
  const Eigen::Matrix3d A = solution.topRows<3>().transpose();
  result.gyro_bias = solution.row(3).transpose();
  // A = Q P with P symmetric positive (the camera's rotations shrunk or stretched along its axes by
  // the 3D-3D fits, the gyro's scale): Q its polar factor.
  result.Q = Polar(A);
  result.rotation_vector = so3::Log(result.Q);
  // r_i(dphi) = a_i - Exp(dphi) A c_i: dr/dphi = [A c_i]x, information sum [A c_i]x^T [A c_i]x.
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();
  double cost = 0;
  for (const Pair& p : pairs_) {
    const Eigen::Matrix3d H = so3::Hat(A * p.theta_camera);
    information += H.transpose() * H;
    cost += (p.theta_gyro - result.gyro_bias * p.dt_s - A * p.theta_camera).squaredNorm();
  }
  const double residual_variance = cost / std::max<double>(1.0, 3.0 * static_cast<double>(pairs_.size()) - 12.0);
  const double smallest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(information).eigenvalues().minCoeff();
  if (smallest > 0) result.sigma_rad = std::sqrt(residual_variance / smallest);
  return result;
}

}  // namespace vio
