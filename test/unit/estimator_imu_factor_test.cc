#include "vio/estimator/imu_factor.h"

#include <memory>
#include <random>

#include <gtest/gtest.h>

#include "estimator_test_support.h"
#include "vio/estimator/pose_manifold.h"

namespace vio {
namespace {

using test::MotionState;
using test::PoseBlock;
using test::RandomVector;
using test::SpeedBiasBlock;
using test::SyntheticMotion;

const Eigen::Vector3d kGravity(0.0, 0.0, -9.81);
const Eigen::Vector3d kGyroBias(0.01, -0.02, 0.015);
const Eigen::Vector3d kAccelBias(0.1, 0.05, -0.08);
constexpr Timestamp kT0Ns = 10'000'000, kT1Ns = 510'000'000;

ImuPreintegration PreintegrateMotion(const SyntheticMotion& motion, const ImuBias& linearization_bias) {
  const auto samples = motion.ImuSamples(0, kT1Ns + 5'000'000, 5'000'000, kGyroBias, kAccelBias);
  return PreintegrateBetween(samples, kT0Ns, kT1Ns, linearization_bias, ImuCalibration());
}

/// Parameter blocks (pose_i, speed_bias_i, pose_j, speed_bias_j) of the true states.
std::vector<std::vector<double>> TrueBlocks(const SyntheticMotion& motion) {
  const MotionState i = motion.At(NanosToSeconds(kT0Ns));
  const MotionState j = motion.At(NanosToSeconds(kT1Ns));
  return {PoseBlock(i.p_w_b, i.q_w_b), SpeedBiasBlock(i.v_w_b, kGyroBias, kAccelBias),
          PoseBlock(j.p_w_b, j.q_w_b), SpeedBiasBlock(j.v_w_b, kGyroBias, kAccelBias)};
}

std::vector<const double*> Pointers(const std::vector<std::vector<double>>& blocks) {
  std::vector<const double*> pointers;
  for (const auto& block : blocks) pointers.push_back(block.data());
  return pointers;
}

TEST(ImuFactor, ResidualVanishesAtTheTrueStates) {
  const SyntheticMotion motion;  // integrated exactly by the midpoint scheme
  const ImuFactor factor(PreintegrateMotion(motion, ImuBias{kGyroBias, kAccelBias}), kGravity);
  const auto blocks = TrueBlocks(motion);
  EXPECT_LT(factor.UnwhitenedResidual(Pointers(blocks).data()).norm(), 1e-10);
  ImuFactor::Vector15d whitened;
  ASSERT_TRUE(factor.Evaluate(Pointers(blocks).data(), whitened.data(), nullptr));
  EXPECT_LT(whitened.norm(), 1e-5);
}

TEST(ImuFactor, BiasCorrectionLeavesASecondOrderResidualAwayFromTheLinearizationBias) {
  const SyntheticMotion motion;
  const auto blocks = TrueBlocks(motion);
  // Residual at the true states when the preintegration is linearized at the
  // true bias moved by `scale` times a fixed offset.
  const auto residual_norm = [&](double scale) {
    const ImuBias offset_bias{kGyroBias + scale * Eigen::Vector3d(2e-3, -2e-3, 1e-3),
                              kAccelBias + scale * Eigen::Vector3d(2e-2, 0.0, -2e-2)};
    const ImuFactor factor(PreintegrateMotion(motion, offset_bias), kGravity);
    return factor.UnwhitenedResidual(Pointers(blocks).data()).norm();
  };
  EXPECT_LT(residual_norm(1.0), 1e-5);
  EXPECT_NEAR(residual_norm(1.0) / residual_norm(0.5), 4.0, 0.2);
}

TEST(ImuFactor, ResidualOrderIsRotationVelocityPositionBiases) {
  const SyntheticMotion motion;
  const ImuFactor factor(PreintegrateMotion(motion, ImuBias{kGyroBias, kAccelBias}), kGravity);
  auto blocks = TrueBlocks(motion);
  blocks[3][0] += 0.1;   // v_j.x
  blocks[2][2] += 0.2;   // p_j.z
  blocks[3][5] += 0.03;  // bg_j.z
  blocks[3][6] += 0.4;   // ba_j.x
  const ImuFactor::Vector15d r = factor.UnwhitenedResidual(Pointers(blocks).data());
  const Eigen::Matrix3d R_i_T = motion.At(NanosToSeconds(kT0Ns)).q_w_b.toRotationMatrix().transpose();
  EXPECT_LT(r.segment<3>(0).norm(), 1e-10);
  EXPECT_LT((r.segment<3>(3) - R_i_T * Eigen::Vector3d(0.1, 0, 0)).norm(), 1e-9);
  EXPECT_LT((r.segment<3>(6) - R_i_T * Eigen::Vector3d(0, 0, 0.2)).norm(), 1e-9);
  EXPECT_LT((r.segment<3>(9) - Eigen::Vector3d(0, 0, 0.03)).norm(), 1e-12);
  EXPECT_LT((r.segment<3>(12) - Eigen::Vector3d(0.4, 0, 0)).norm(), 1e-12);
}

TEST(ImuFactor, JacobiansMatchCentralDifferencesOnTheTangentSpace) {
  const SyntheticMotion motion = SyntheticMotion::Wavy();
  const ImuBias linearization_bias{Eigen::Vector3d(0.02, 0.0, -0.01), Eigen::Vector3d(0.0, 0.1, 0.05)};
  const ImuFactor factor(PreintegrateMotion(motion, linearization_bias), kGravity);
  const PoseManifold pose_manifold;
  std::mt19937 rng(17);
  for (int trial = 0; trial < 10; ++trial) {
    auto blocks = TrueBlocks(motion);
    for (int b : {0, 2}) {
      Eigen::Matrix<double, 6, 1> delta;
      delta << RandomVector<3>(rng, 0.5), RandomVector<3>(rng, 0.4);
      std::vector<double> perturbed(7);
      pose_manifold.Plus(blocks[b].data(), delta.data(), perturbed.data());
      blocks[b] = perturbed;
    }
    for (int b : {1, 3}) {
      const Eigen::Matrix<double, 9, 1> delta = RandomVector<9>(rng, 0.05);
      for (int k = 0; k < 9; ++k) blocks[b][k] += delta[k] * (k < 3 ? 10.0 : 1.0);
    }
    test::ExpectTangentJacobiansMatch(factor, blocks, {&pose_manifold, nullptr, &pose_manifold, nullptr},
                                      1e-6);
    test::ExpectTangentEvaluationMatchesAmbient(factor, blocks,
                                                {&pose_manifold, nullptr, &pose_manifold, nullptr});
  }
}

TEST(ImuFactor, UsesTheGivenGravity) {
  const SyntheticMotion motion;
  const ImuFactor factor(PreintegrateMotion(motion, ImuBias{kGyroBias, kAccelBias}),
                         Eigen::Vector3d(0.0, 0.0, -9.80));
  const auto blocks = TrueBlocks(motion);
  // 0.01 m/s^2 of gravity error over 0.5 s: 5 mm/s and 1.25 mm.
  const ImuFactor::Vector15d r = factor.UnwhitenedResidual(Pointers(blocks).data());
  EXPECT_NEAR(r.segment<3>(3).norm(), 0.005, 1e-9);
  EXPECT_NEAR(r.segment<3>(6).norm(), 0.00125, 1e-9);
}

}  // namespace
}  // namespace vio
