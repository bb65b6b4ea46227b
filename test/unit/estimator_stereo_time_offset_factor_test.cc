// StereoTimeOffsetFactor: StereoFactor's residual with the measurement moved along its image
// velocity by (t_d - t_a); Jacobians (pose, landmark and the offset) against central differences.
#include "vio/estimator/stereo_time_offset_factor.h"

#include <random>

#include <gtest/gtest.h>

#include "estimator_test_support.h"
#include "vio/estimator/pose_manifold.h"
#include "vio/estimator/so3.h"

namespace vio {
namespace {

using test::PoseBlock;
using test::RandomVector;

RectifiedStereo SideLookingStereo() {
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

TEST(StereoTimeOffsetFactor, ResidualIsStereoFactorsAtTheShiftedMeasurement) {
  const RectifiedStereo stereo = SideLookingStereo();
  const Eigen::Vector3d p_w_b(0.5, -1.0, 1.2), p_w_l(5.0, -0.5, 2.0);
  const Eigen::Quaterniond q_w_b = so3::ExpQuaternion(Eigen::Vector3d(0.1, -0.05, 0.3));
  const Eigen::Vector3d z(310.0, 290.0, 201.0), velocity(40.0, 38.0, -12.0);
  const double t_a = 0.004, t_d = 0.019;
  const StereoTimeOffsetFactor factor(z, velocity, t_a, stereo, 0.7);
  const StereoFactor shifted(z + (t_d - t_a) * velocity, stereo, 0.7);
  const std::vector<double> pose = PoseBlock(p_w_b, q_w_b);
  const double landmark[3] = {p_w_l.x(), p_w_l.y(), p_w_l.z()};
  const double offset[1] = {t_d};
  const double* parameters[3] = {pose.data(), landmark, offset};
  Eigen::Vector3d expected, residual;
  ASSERT_TRUE(shifted.Evaluate(parameters, expected.data(), nullptr));
  ASSERT_TRUE(factor.Evaluate(parameters, residual.data(), nullptr));
  EXPECT_LT((residual - expected).norm(), 1e-12);
}

TEST(StereoTimeOffsetFactor, JacobiansMatchCentralDifferencesOnTheTangentSpace) {
  const RectifiedStereo stereo = SideLookingStereo();
  const PoseManifold pose_manifold;
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Vector3d p_w_b = RandomVector<3>(rng, 2.0);
    const Eigen::Quaterniond q_w_b = so3::ExpQuaternion(RandomVector<3>(rng, 0.3));
    const Eigen::Vector3d p_c(RandomVector<1>(rng, 2.0)[0], RandomVector<1>(rng, 1.5)[0],
                              6.0 + RandomVector<1>(rng, 4.0)[0]);
    const Eigen::Vector3d p_w_l = p_w_b + q_w_b * (stereo.T_b_cl * p_c);
    const Eigen::Vector3d velocity = RandomVector<3>(rng, 200.0);
    const double t_a = RandomVector<1>(rng, 0.02)[0];
    const StereoTimeOffsetFactor factor(Eigen::Vector3d(300.0, 280.0, 200.0), velocity, t_a, stereo, 0.8);
    const std::vector<std::vector<double>> blocks = {
        PoseBlock(p_w_b, q_w_b), {p_w_l.x(), p_w_l.y(), p_w_l.z()}, {RandomVector<1>(rng, 0.05)[0]}};
    test::ExpectTangentJacobiansMatch(factor, blocks, {&pose_manifold, nullptr, nullptr}, 1e-6);
    test::ExpectTangentEvaluationMatchesAmbient(factor, blocks, {&pose_manifold, nullptr, nullptr});
  }
}

}  // namespace
}  // namespace vio
