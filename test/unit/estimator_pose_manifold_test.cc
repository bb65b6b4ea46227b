#include "vio/estimator/pose_manifold.h"

#include <random>

#include <ceres/manifold_test_utils.h>
#include <gtest/gtest.h>

#include "estimator_test_support.h"

namespace vio {
namespace {

using ceres::Matrix;
using ceres::Vector;
using test::RandomVector;

constexpr double kTolerance = 1e-9;

/// A random pose block (unit quaternion).
Vector RandomPose(std::mt19937& rng) {
  const std::vector<double> block =
      test::PoseBlock(RandomVector<3>(rng, 5.0), so3::ExpQuaternion(RandomVector<3>(rng, 1.7)));
  return Eigen::Map<const Vector>(block.data(), kPoseSize);
}

/// All of Ceres' manifold invariants at (x, delta, y).
void ExpectInvariants(const Vector& x, const Vector& delta, const Vector& y) {
  using namespace ceres;  // the matchers of manifold_test_utils.h
  const PoseManifold manifold;
  EXPECT_THAT_MANIFOLD_INVARIANTS_HOLD(manifold, x, delta, y, kTolerance);
}

TEST(PoseManifold, SatisfiesCeresInvariantsAtRandomPoints) {
  std::mt19937 rng(42);
  const PoseManifold manifold;
  for (int trial = 0; trial < 20; ++trial) {
    const Vector x = RandomPose(rng);
    Vector delta(6);
    delta << RandomVector<3>(rng, 2.0), RandomVector<3>(rng, 1.5);
    // y = x [+] (|dtheta| < pi): Minus recovers the shortest rotation exactly.
    Vector y_delta(6);
    y_delta << RandomVector<3>(rng, 2.0), RandomVector<3>(rng, 1.5);
    Vector y(7);
    manifold.Plus(x.data(), y_delta.data(), y.data());
    ExpectInvariants(x, delta, y);
  }
}

TEST(PoseManifold, SatisfiesCeresInvariantsAtIdentityAndSmallDeltas) {
  Vector identity = Vector::Zero(7);
  identity[6] = 1.0;
  Vector small_delta(6);
  small_delta << 1e-9, -2e-9, 3e-9, 1e-10, 2e-10, -1e-10;
  ExpectInvariants(identity, small_delta, identity);
}

TEST(PoseManifold, PlusPerturbsTheRotationOnTheRight) {
  std::mt19937 rng(3);
  const PoseManifold manifold;
  const Vector x = RandomPose(rng);
  const Eigen::Vector3d dp(0.1, -0.2, 0.3), dtheta(0.2, 0.1, -0.3);
  Vector delta(6);
  delta << dp, dtheta;
  Vector result(7);
  ASSERT_TRUE(manifold.Plus(x.data(), delta.data(), result.data()));
  const Eigen::Quaterniond q_x(x[6], x[3], x[4], x[5]);
  const Eigen::Quaterniond q_result(result[6], result[3], result[4], result[5]);
  EXPECT_TRUE(result.head<3>().isApprox(x.head<3>() + dp, 1e-15));
  EXPECT_LT((q_result.toRotationMatrix() - q_x.toRotationMatrix() * so3::Exp(dtheta)).norm(), 1e-14);
}

TEST(PoseManifold, MinusIgnoresTheQuaternionSign) {
  std::mt19937 rng(5);
  const PoseManifold manifold;
  const Vector x = RandomPose(rng);
  Vector y = RandomPose(rng);
  Vector expected(6), flipped(6);
  ASSERT_TRUE(manifold.Minus(y.data(), x.data(), expected.data()));
  y.tail<4>() *= -1.0;
  ASSERT_TRUE(manifold.Minus(y.data(), x.data(), flipped.data()));
  EXPECT_LT((expected - flipped).norm(), 1e-14);
  EXPECT_LE(expected.tail<3>().norm(), 3.14159265358979323846 + 1e-12);
}

TEST(PoseManifold, AmbientJacobianTimesPlusJacobianIsTheTangentJacobian) {
  std::mt19937 rng(11);
  const PoseManifold manifold;
  for (int trial = 0; trial < 10; ++trial) {
    const Vector x = RandomPose(rng);
    const Eigen::Quaterniond q(x[6], x[3], x[4], x[5]);
    const Eigen::Matrix<double, 4, 6> J_tangent = Eigen::Matrix<double, 4, 6>::Random();
    Eigen::Matrix<double, 4, 7, Eigen::RowMajor> J_ambient;
    PoseJacobianToAmbient<4>(J_tangent, q, J_ambient.data());
    Eigen::Matrix<double, 7, 6, Eigen::RowMajor> plus_jacobian;
    ASSERT_TRUE(manifold.PlusJacobian(x.data(), plus_jacobian.data()));
    EXPECT_LT((J_ambient * plus_jacobian - J_tangent).norm(), 1e-14);
  }
}

TEST(PoseManifold, MinusTangentJacobianMatchesCentralDifferences) {
  std::mt19937 rng(13);
  const PoseManifold manifold;
  const double h = 1e-6;
  for (int trial = 0; trial < 10; ++trial) {
    const Vector x = RandomPose(rng);
    // x0 within 2.6 rad of x: away from the cut of Log at pi.
    Vector x0_delta(6);
    x0_delta << RandomVector<3>(rng, 2.0), RandomVector<3>(rng, 1.5);
    Vector x0(7);
    manifold.Plus(x.data(), x0_delta.data(), x0.data());
    if (trial % 2 == 1) x0.tail<4>() *= -1.0;  // either quaternion sign
    Eigen::Matrix<double, 6, 6> numeric;
    for (int k = 0; k < 6; ++k) {
      const Vector delta = h * Vector::Unit(6, k);
      Vector x_plus(7), x_minus(7), minus_plus(6), minus_minus(6);
      manifold.Plus(x.data(), delta.data(), x_plus.data());
      manifold.Plus(x.data(), (-delta).eval().data(), x_minus.data());
      manifold.Minus(x_plus.data(), x0.data(), minus_plus.data());
      manifold.Minus(x_minus.data(), x0.data(), minus_minus.data());
      numeric.col(k) = (minus_plus - minus_minus) / (2.0 * h);
    }
    Eigen::Matrix<double, 6, 6, Eigen::RowMajor> analytic;
    ASSERT_TRUE(manifold.MinusTangentJacobian(x.data(), x0.data(), analytic.data()));
    EXPECT_LT((analytic - numeric).norm(), 1e-7) << "analytic\n" << analytic << "\nnumeric\n" << numeric;
  }
}

TEST(PoseManifold, QuaternionMinusJacobianIsTheScaledTransposeOfPlusJacobian) {
  const Eigen::Quaterniond q = so3::ExpQuaternion(Eigen::Vector3d(0.3, -1.1, 0.8));
  const Eigen::Matrix<double, 4, 3> plus = QuaternionPlusJacobian(q);
  const Eigen::Matrix<double, 3, 4> minus = QuaternionMinusJacobian(q);
  EXPECT_LT((minus - 4.0 * plus.transpose()).norm(), 1e-15);
  EXPECT_LT((minus * plus - Eigen::Matrix3d::Identity()).norm(), 1e-15);
  // The normal direction (scaling q) is in the null space of the minus Jacobian.
  EXPECT_LT((minus * q.coeffs()).norm(), 1e-15);
}

}  // namespace
}  // namespace vio
