#include "vio/estimator/stereo_factor.h"

#include <memory>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include "estimator_test_support.h"
#include "vio/estimator/pose_manifold.h"

namespace vio {
namespace {

using test::PoseBlock;
using test::RandomVector;

/// A rectified rig whose left camera looks along the body x axis.
RectifiedStereo ForwardLookingStereo() {
  RectifiedStereo stereo;
  stereo.f = 450.0;
  stereo.cx = 370.0;
  stereo.cy = 245.0;
  stereo.baseline = 0.11;
  Eigen::Matrix3d R_b_c;
  R_b_c.col(0) = -Eigen::Vector3d::UnitY();  // camera x = body -y
  R_b_c.col(1) = -Eigen::Vector3d::UnitZ();  // camera y = body -z
  R_b_c.col(2) = Eigen::Vector3d::UnitX();   // camera z = body x
  stereo.T_b_cl.linear() = R_b_c;
  stereo.T_b_cl.translation() = Eigen::Vector3d(0.05, -0.02, 0.01);
  return stereo;
}

std::vector<const double*> Pointers(const std::vector<std::vector<double>>& blocks) {
  return {blocks[0].data(), blocks[1].data()};
}

TEST(StereoFactor, PredictsThePinholeProjectionInBothCameras) {
  RectifiedStereo stereo;  // camera = body
  const Eigen::Vector3d p_w_l(0.4, -0.3, 4.0);
  Eigen::Vector3d z;
  ASSERT_TRUE(StereoFactor::Project(stereo, Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity(),
                                    p_w_l, &z));
  EXPECT_NEAR(z[0], stereo.f * 0.1 + stereo.cx, 1e-12);
  EXPECT_NEAR(z[2], stereo.f * -0.075 + stereo.cy, 1e-12);
  EXPECT_NEAR(z[0] - z[1], stereo.f * stereo.baseline / 4.0, 1e-12);  // disparity
}

TEST(StereoFactor, ResidualIsTheWhitenedReprojectionError) {
  const RectifiedStereo stereo = ForwardLookingStereo();
  const Eigen::Vector3d p_w_b(1.0, 2.0, 0.5), p_w_l(6.0, 2.5, 1.0);
  const Eigen::Quaterniond q_w_b = so3::ExpQuaternion(Eigen::Vector3d(0.05, -0.1, 0.2));
  Eigen::Vector3d predicted;
  ASSERT_TRUE(StereoFactor::Project(stereo, p_w_b, q_w_b, p_w_l, &predicted));
  const Eigen::Vector3d offset(1.5, -0.5, 2.0);
  const StereoFactor factor(predicted + offset, stereo, 0.5);
  const std::vector<std::vector<double>> blocks = {PoseBlock(p_w_b, q_w_b), {p_w_l.x(), p_w_l.y(), p_w_l.z()}};
  Eigen::Vector3d residual;
  ASSERT_TRUE(factor.Evaluate(Pointers(blocks).data(), residual.data(), nullptr));
  EXPECT_LT((residual - offset / 0.5).norm(), 1e-9);
}

TEST(StereoFactor, JacobiansMatchCentralDifferencesOnTheTangentSpace) {
  const RectifiedStereo stereo = ForwardLookingStereo();
  const PoseManifold pose_manifold;
  std::mt19937 rng(23);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Vector3d p_w_b = RandomVector<3>(rng, 2.0);
    const Eigen::Quaterniond q_w_b = so3::ExpQuaternion(RandomVector<3>(rng, 0.3));
    // A landmark 2..10 m in front of the camera.
    const Eigen::Vector3d p_c(RandomVector<1>(rng, 2.0)[0], RandomVector<1>(rng, 1.5)[0],
                              6.0 + RandomVector<1>(rng, 4.0)[0]);
    const Eigen::Vector3d p_w_l = p_w_b + q_w_b * (stereo.T_b_cl * p_c);
    const StereoFactor factor(Eigen::Vector3d(300.0, 280.0, 200.0), stereo, 0.8);
    test::ExpectTangentJacobiansMatch(factor, {PoseBlock(p_w_b, q_w_b), {p_w_l.x(), p_w_l.y(), p_w_l.z()}},
                                      {&pose_manifold, nullptr}, 1e-6);
    test::ExpectTangentEvaluationMatchesAmbient(
        factor, {PoseBlock(p_w_b, q_w_b), {p_w_l.x(), p_w_l.y(), p_w_l.z()}}, {&pose_manifold, nullptr});
  }
}

TEST(StereoFactor, RejectsLandmarksBehindTheCamera) {
  const RectifiedStereo stereo = ForwardLookingStereo();
  const std::vector<std::vector<double>> blocks = {PoseBlock(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity()),
                                                   {-3.0, 0.0, 0.0}};
  const StereoFactor factor(Eigen::Vector3d(300.0, 280.0, 200.0), stereo, 1.0);
  Eigen::Vector3d residual;
  EXPECT_FALSE(factor.Evaluate(Pointers(blocks).data(), residual.data(), nullptr));
  Eigen::Vector3d z = Eigen::Vector3d::Constant(-1.0);
  EXPECT_FALSE(StereoFactor::Project(stereo, Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity(),
                                     Eigen::Vector3d(-3.0, 0.0, 0.0), &z));
  EXPECT_EQ(z, Eigen::Vector3d::Constant(-1.0));
}

// Factors made with one shared rig hold it without a copy of their own (a window's factors), and
// evaluate to the last bit as a factor with its own copy does.
TEST(StereoFactor, FactorsShareOneRigAndEvaluateAsWithACopy) {
  const auto rig = std::make_shared<const RectifiedStereo>(ForwardLookingStereo());
  const Eigen::Vector3d z(300.0, 280.0, 200.0);
  const StereoFactor first(z, rig, 0.8);
  const std::unique_ptr<ceres::CostFunction> second(StereoFactor::Create(z, rig, 0.8));
  EXPECT_EQ(rig.use_count(), 3);
  const StereoFactor copy(z, ForwardLookingStereo(), 0.8);
  const std::vector<std::vector<double>> blocks = {PoseBlock(Eigen::Vector3d(-2.0, 0.1, 0.2), Eigen::Quaterniond(
                                                                 Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ()))),
                                                   {1.0, 0.3, -0.2}};
  Eigen::Vector3d r_shared, r_copy;
  Eigen::Matrix<double, 3, 7, Eigen::RowMajor> J_shared, J_copy;
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> L_shared, L_copy;
  double* jacobians_shared[2] = {J_shared.data(), L_shared.data()};
  double* jacobians_copy[2] = {J_copy.data(), L_copy.data()};
  ASSERT_TRUE(second->Evaluate(Pointers(blocks).data(), r_shared.data(), jacobians_shared));
  ASSERT_TRUE(copy.Evaluate(Pointers(blocks).data(), r_copy.data(), jacobians_copy));
  EXPECT_EQ(r_shared, r_copy);
  EXPECT_EQ(J_shared, J_copy);
  EXPECT_EQ(L_shared, L_copy);
}

TEST(StereoFactor, RejectsANullRig) {
  EXPECT_THROW(StereoFactor(Eigen::Vector3d::Zero(), std::shared_ptr<const RectifiedStereo>(), 1.0),
               std::invalid_argument);
}

TEST(StereoFactor, RejectsNonPositiveSigma) {
  EXPECT_THROW(StereoFactor(Eigen::Vector3d::Zero(), RectifiedStereo(), 0.0), std::invalid_argument);
  EXPECT_THROW(StereoFactor::Create(Eigen::Vector3d::Zero(), RectifiedStereo(), -1.0), std::invalid_argument);
}

}  // namespace
}  // namespace vio
