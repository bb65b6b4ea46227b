#include "vio/estimator/so3.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "estimator_test_support.h"

namespace vio::so3 {
namespace {

using test::RandomVector;

constexpr double kPi = 3.14159265358979323846;

/// Rotation vectors covering tiny, small, generic and near-pi angles.
std::vector<Eigen::Vector3d> TestRotationVectors() {
  std::mt19937 rng(7);
  std::vector<Eigen::Vector3d> thetas = {Eigen::Vector3d::Zero(), Eigen::Vector3d(1e-9, -2e-9, 3e-9),
                                         Eigen::Vector3d(3e-5, 1e-5, -2e-5),
                                         (kPi - 1e-6) * Eigen::Vector3d(1, -2, 2).normalized()};
  for (int i = 0; i < 20; ++i) thetas.push_back(RandomVector<3>(rng, 1.7));
  return thetas;
}

TEST(So3, HatIsTheCrossProduct) {
  const Eigen::Vector3d w(0.3, -1.2, 2.0), v(-0.7, 0.4, 1.1);
  EXPECT_TRUE((Hat(w) * v).isApprox(w.cross(v), 1e-15));
}

TEST(So3, ExpMatchesAngleAxis) {
  for (const Eigen::Vector3d& theta : TestRotationVectors()) {
    if (theta.norm() == 0.0) continue;
    const Eigen::Matrix3d expected = Eigen::AngleAxisd(theta.norm(), theta.normalized()).toRotationMatrix();
    EXPECT_LT((Exp(theta) - expected).norm(), 1e-14) << theta.transpose();
    EXPECT_NEAR(ExpQuaternion(theta).norm(), 1.0, 1e-15);
  }
}

TEST(So3, LogInvertsExp) {
  for (const Eigen::Vector3d& theta : TestRotationVectors()) {
    EXPECT_LT((Log(ExpQuaternion(theta)) - theta).norm(), 1e-12 * std::max(1.0, theta.norm()))
        << theta.transpose();
    EXPECT_LT((Log(Exp(theta)) - theta).norm(), 1e-8) << theta.transpose();
  }
}

TEST(So3, LogIgnoresQuaternionSignAndTakesShortestRotation) {
  const Eigen::Vector3d theta(0.4, -0.9, 1.3);
  const Eigen::Quaterniond q = ExpQuaternion(theta);
  const Eigen::Quaterniond minus_q(-q.w(), -q.x(), -q.y(), -q.z());
  EXPECT_LT((Log(minus_q) - theta).norm(), 1e-14);
  // A 3 pi / 2 rotation is the -pi / 2 rotation about the same axis.
  const Eigen::Vector3d axis = Eigen::Vector3d(1, 1, 0).normalized();
  EXPECT_LT((Log(ExpQuaternion(1.5 * kPi * axis)) + 0.5 * kPi * axis).norm(), 1e-12);
}

TEST(So3, RightJacobianMatchesCentralDifferences) {
  const double h = 1e-6;
  for (const Eigen::Vector3d& theta : TestRotationVectors()) {
    if (theta.norm() > 3.0) continue;  // Log wraps near pi
    Eigen::Matrix3d numeric;
    const Eigen::Quaterniond q_inverse = ExpQuaternion(theta).conjugate();
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d d = h * Eigen::Vector3d::Unit(k);
      numeric.col(k) = (Log(q_inverse * ExpQuaternion(theta + d)) -
                        Log(q_inverse * ExpQuaternion(theta - d))) / (2.0 * h);
    }
    EXPECT_LT((RightJacobian(theta) - numeric).norm(), 1e-8) << theta.transpose();
  }
}

TEST(So3, RightJacobianInverseMatchesCentralDifferences) {
  const double h = 1e-6;
  for (const Eigen::Vector3d& theta : TestRotationVectors()) {
    if (theta.norm() > 3.0) continue;
    Eigen::Matrix3d numeric;
    const Eigen::Quaterniond q = ExpQuaternion(theta);
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d d = h * Eigen::Vector3d::Unit(k);
      numeric.col(k) = (Log(q * ExpQuaternion(d)) - Log(q * ExpQuaternion(-d))) / (2.0 * h);
    }
    EXPECT_LT((RightJacobianInverse(theta) - numeric).norm(), 1e-7) << theta.transpose();
    EXPECT_LT((RightJacobianInverse(theta) * RightJacobian(theta) - Eigen::Matrix3d::Identity()).norm(),
              1e-12) << theta.transpose();
  }
}

}  // namespace
}  // namespace vio::so3
