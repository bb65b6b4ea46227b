#include <memory>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include "estimator_test_support.h"
#include "vio/estimator/pose_manifold.h"
#include "vio/estimator/pose_prior_factor.h"
#include "vio/estimator/speed_bias_prior_factor.h"

namespace vio {
namespace {

using test::PoseBlock;
using test::RandomVector;

TEST(PosePriorFactor, ResidualIsTheWhitenedTangentOffset) {
  const Eigen::Vector3d p0(1.0, -2.0, 3.0);
  const Eigen::Quaterniond q0 = so3::ExpQuaternion(Eigen::Vector3d(0.3, 0.2, -0.1));
  const Eigen::Vector3d dp(0.1, 0.2, -0.3), dtheta(0.05, -0.02, 0.01);
  std::unique_ptr<ceres::CostFunction> factor(PosePriorFactor::Create(p0, q0, 0.5, 0.01));
  const std::vector<double> pose = PoseBlock(p0 + dp, q0 * so3::ExpQuaternion(dtheta));
  const double* blocks[] = {pose.data()};
  Eigen::Matrix<double, 6, 1> residual, expected;
  ASSERT_TRUE(factor->Evaluate(blocks, residual.data(), nullptr));
  expected << dp / 0.5, dtheta / 0.01;
  EXPECT_LT((residual - expected).norm(), 1e-10);
}

TEST(PosePriorFactor, JacobiansMatchCentralDifferencesOnTheTangentSpace) {
  std::mt19937 rng(31);
  const PoseManifold pose_manifold;
  for (int trial = 0; trial < 10; ++trial) {
    Eigen::Matrix<double, 6, 6> sqrt_information = Eigen::Matrix<double, 6, 6>::Random();
    sqrt_information.diagonal().array() += 3.0;
    const Eigen::Quaterniond q_prior = so3::ExpQuaternion(RandomVector<3>(rng, 1.5));
    const PosePriorFactor factor(RandomVector<3>(rng, 3.0), q_prior, sqrt_information);
    // Within 2.6 rad of the prior: away from the cut of Log at pi.
    const std::vector<double> pose =
        PoseBlock(RandomVector<3>(rng, 3.0), q_prior * so3::ExpQuaternion(RandomVector<3>(rng, 1.5)));
    test::ExpectTangentJacobiansMatch(factor, {pose}, {&pose_manifold}, 1e-6);
  }
}

TEST(PosePriorFactor, AmbientJacobianIsTheExactAmbientDerivative) {
  const PosePriorFactor factor(Eigen::Vector3d(1, 2, 3), so3::ExpQuaternion(Eigen::Vector3d(0.2, -0.4, 0.1)),
                               Eigen::Matrix<double, 6, 6>::Identity());
  const std::vector<double> pose =
      PoseBlock(Eigen::Vector3d(1.5, 2.2, 2.0), so3::ExpQuaternion(Eigen::Vector3d(0.5, 0.3, -0.6)));
  // Ambient (7-dim, Euclidean) central differences of the unnormalized block.
  std::vector<Eigen::MatrixXd> analytic, numeric;
  test::TangentJacobians(factor, {pose}, {nullptr}, 1e-6, &analytic, &numeric);
  EXPECT_LT((analytic[0] - numeric[0]).norm(), 1e-7 * numeric[0].norm()) << analytic[0] << "\n\n" << numeric[0];
}

TEST(PosePriorFactor, RejectsNonPositiveSigmas) {
  EXPECT_THROW(PosePriorFactor::Create(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity(), 0.0, 1.0),
               std::invalid_argument);
}

TEST(SpeedBiasPriorFactor, ResidualAndJacobianAreTheWhitenedOffset) {
  std::mt19937 rng(37);
  const SpeedBiasPriorFactor::Vector9d prior = RandomVector<9>(rng, 1.0);
  const SpeedBiasPriorFactor::Vector9d offset = RandomVector<9>(rng, 0.1);
  std::unique_ptr<ceres::CostFunction> factor(SpeedBiasPriorFactor::Create(prior, 0.1, 0.01, 0.2));
  const SpeedBiasPriorFactor::Vector9d x = prior + offset;
  const double* blocks[] = {x.data()};
  SpeedBiasPriorFactor::Vector9d residual, expected;
  ASSERT_TRUE(factor->Evaluate(blocks, residual.data(), nullptr));
  expected << offset.head<3>() / 0.1, offset.segment<3>(3) / 0.01, offset.tail<3>() / 0.2;
  EXPECT_LT((residual - expected).norm(), 1e-12);
  test::ExpectTangentJacobiansMatch(*factor, {std::vector<double>(x.data(), x.data() + 9)}, {nullptr}, 1e-7);
}

TEST(SpeedBiasPriorFactor, RejectsNonPositiveSigmas) {
  EXPECT_THROW(SpeedBiasPriorFactor::Create(SpeedBiasPriorFactor::Vector9d::Zero(), 1.0, -1.0, 1.0),
               std::invalid_argument);
}

}  // namespace
}  // namespace vio
