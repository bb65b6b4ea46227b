// StereoExtrinsicFactor: StereoFactor's residual at the corrected rig; Jacobians (pose, landmark and
// the extrinsic correction) against central differences.
#include "vio/estimator/stereo_extrinsic_factor.h"

#include <random>

#include <gtest/gtest.h>

#include "estimator_test_support.h"
#include "vio/estimator/pose_manifold.h"
#include "vio/estimator/so3.h"

namespace vio {
namespace {

using test::PoseBlock;
using test::RandomVector;

RectifiedStereo ForwardStereo() {
  RectifiedStereo stereo;
  stereo.f = 458.0;
  stereo.cx = 367.0;
  stereo.cy = 248.0;
  stereo.baseline = 0.11;
  Eigen::Matrix3d R_b_c;
  R_b_c.col(0) = -Eigen::Vector3d::UnitY();
  R_b_c.col(1) = -Eigen::Vector3d::UnitZ();
  R_b_c.col(2) = Eigen::Vector3d::UnitX();
  stereo.T_b_cl.linear() = R_b_c;
  stereo.T_b_cl.translation() = Eigen::Vector3d(-0.02, -0.06, 0.01);
  return stereo;
}

std::vector<double> ToBlock(const Eigen::Matrix<double, 6, 1>& c) { return {c.data(), c.data() + 6}; }

TEST(StereoExtrinsicFactor, ResidualIsStereoFactorsAtTheCorrectedRig) {
  const RectifiedStereo stereo = ForwardStereo();
  const Eigen::Vector3d p_w_b(0.5, -1.0, 1.2), p_w_l(5.0, -0.5, 2.0), z(310.0, 290.0, 201.0);
  const Eigen::Quaterniond q_w_b = so3::ExpQuaternion(Eigen::Vector3d(0.1, -0.05, 0.3));
  Eigen::Matrix<double, 6, 1> correction;
  correction << 0.01, -0.02, 0.015, 0.01, -0.02, 0.005;
  const StereoExtrinsicFactor factor(z, stereo, 0.7);
  const StereoFactor corrected(z, CorrectedStereo(stereo, correction), 0.7);
  const StereoFactor plain(z, stereo, 0.7);
  const std::vector<double> pose = PoseBlock(p_w_b, q_w_b), c = ToBlock(correction);
  const std::vector<double> zero(6, 0.0);
  const double landmark[3] = {p_w_l.x(), p_w_l.y(), p_w_l.z()};
  const double* parameters[3] = {pose.data(), landmark, c.data()};
  Eigen::Vector3d expected, residual;
  ASSERT_TRUE(corrected.Evaluate(parameters, expected.data(), nullptr));
  ASSERT_TRUE(factor.Evaluate(parameters, residual.data(), nullptr));
  EXPECT_LT((residual - expected).norm(), 1e-12);
  parameters[2] = zero.data();
  ASSERT_TRUE(plain.Evaluate(parameters, expected.data(), nullptr));
  ASSERT_TRUE(factor.Evaluate(parameters, residual.data(), nullptr));
  EXPECT_LT((residual - expected).norm(), 1e-12);
}

TEST(StereoExtrinsicFactor, ExtrinsicJacobianAloneEqualsTheOneWithAllBlocks) {
  const RectifiedStereo stereo = ForwardStereo();
  const Eigen::Quaterniond q_w_b = so3::ExpQuaternion(Eigen::Vector3d(0.1, -0.05, 0.3));
  const std::vector<double> pose = PoseBlock(Eigen::Vector3d(0.5, -1.0, 1.2), q_w_b);
  const std::vector<double> c = {0.01, -0.02, 0.015, 0.01, -0.02, 0.005};
  const double landmark[3] = {5.0, -0.5, 2.0};
  const double* parameters[3] = {pose.data(), landmark, c.data()};
  const StereoExtrinsicFactor factor(Eigen::Vector3d(310.0, 290.0, 201.0), stereo, 0.7);
  double J_pose[21], J_landmark[9], J_all[18], J_alone[18];
  double* all[3] = {J_pose, J_landmark, J_all};
  double* alone[3] = {nullptr, nullptr, J_alone};
  Eigen::Vector3d r_all, r_alone;
  ASSERT_TRUE(factor.Evaluate(parameters, r_all.data(), all));
  ASSERT_TRUE(factor.Evaluate(parameters, r_alone.data(), alone));
  EXPECT_EQ(r_all, r_alone);
  for (int i = 0; i < 18; ++i) EXPECT_EQ(J_all[i], J_alone[i]) << i;
}

TEST(StereoExtrinsicFactor, CorrectedStereoRotatesAndTranslatesTheLeftCameraOnly) {
  const RectifiedStereo stereo = ForwardStereo();
  Eigen::Matrix<double, 6, 1> correction;
  correction << 0.0, 0.0, 0.02, 0.01, 0.0, -0.015;
  const RectifiedStereo rig = CorrectedStereo(stereo, correction);
  const Eigen::Matrix3d expected = stereo.T_b_cl.linear() * so3::Exp(Eigen::Vector3d(0.0, 0.0, 0.02));
  EXPECT_LT((rig.T_b_cl.linear() - expected).norm(), 1e-12);
  EXPECT_LT((rig.T_b_cl.translation() - stereo.T_b_cl.translation() - correction.tail<3>()).norm(), 1e-12);
  EXPECT_EQ(rig.baseline, stereo.baseline);
  EXPECT_EQ(rig.f, stereo.f);
}

TEST(StereoExtrinsicFactor, JacobiansMatchCentralDifferencesOnTheTangentSpace) {
  const RectifiedStereo stereo = ForwardStereo();
  const PoseManifold pose_manifold;
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Vector3d p_w_b = RandomVector<3>(rng, 2.0);
    const Eigen::Quaterniond q_w_b = so3::ExpQuaternion(RandomVector<3>(rng, 0.3));
    const Eigen::Vector3d p_c(RandomVector<1>(rng, 2.0)[0], RandomVector<1>(rng, 1.5)[0],
                              6.0 + RandomVector<1>(rng, 4.0)[0]);
    const Eigen::Vector3d p_w_l = p_w_b + q_w_b * (stereo.T_b_cl * p_c);
    Eigen::Matrix<double, 6, 1> correction;
    correction << RandomVector<3>(rng, 0.05), RandomVector<3>(rng, 0.03);
    const StereoExtrinsicFactor factor(Eigen::Vector3d(300.0, 280.0, 200.0), stereo, 0.8);
    const std::vector<std::vector<double>> blocks = {
        PoseBlock(p_w_b, q_w_b), {p_w_l.x(), p_w_l.y(), p_w_l.z()}, ToBlock(correction)};
    test::ExpectTangentJacobiansMatch(factor, blocks, {&pose_manifold, nullptr, nullptr}, 1e-6);
    test::ExpectTangentEvaluationMatchesAmbient(factor, blocks, {&pose_manifold, nullptr, nullptr});
  }
}

TEST(StereoExtrinsicFactor, RejectsNonPositiveSigma) {
  EXPECT_THROW(StereoExtrinsicFactor(Eigen::Vector3d::Zero(), ForwardStereo(), 0.0), std::invalid_argument);
}

}  // namespace
}  // namespace vio
