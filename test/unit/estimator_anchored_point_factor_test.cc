// The local map's summary of dropped frames' observations: the anchored-point
// factor's Jacobians, and the summary's cost against the observations it
// summarizes.
#include "vio/estimator/anchored_point_factor.h"

#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "estimator_test_support.h"
#include "vio/estimator/pose_manifold.h"
#include "vio/estimator/so3.h"
#include "vio/estimator/stereo_factor.h"

namespace vio {
namespace {

using test::PoseBlock;
using test::RandomVector;

std::vector<double> PointBlock(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }

TEST(AnchoredPointFactor, ResidualIsTheWhitenedPointInTheBody) {
  const Eigen::Vector3d p_w_b(1.0, -2.0, 0.5), p_w_l(3.0, 1.0, 2.0), p_b_hat(0.1, 0.2, 0.3);
  const Eigen::Quaterniond q_w_b = so3::ExpQuaternion(Eigen::Vector3d(0.3, -0.2, 0.9));
  Eigen::Matrix3d L;
  L << 2.0, 0.5, -0.1, 0.0, 3.0, 0.2, 0.0, 0.0, 1.5;
  const AnchoredPointFactor factor(p_b_hat, L);
  const std::vector<double> pose = PoseBlock(p_w_b, q_w_b), point = PointBlock(p_w_l);
  const double* blocks[2] = {pose.data(), point.data()};
  Eigen::Vector3d r;
  ASSERT_TRUE(factor.Evaluate(blocks, r.data(), nullptr));
  EXPECT_LT((r - L * (q_w_b.conjugate() * (p_w_l - p_w_b) - p_b_hat)).norm(), 1e-12);
}

TEST(AnchoredPointFactor, JacobiansMatchCentralDifferencesOnTheTangentSpace) {
  const PoseManifold pose_manifold;
  std::mt19937 rng(31);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Vector3d p_w_b = RandomVector<3>(rng, 2.0), p_w_l = RandomVector<3>(rng, 5.0);
    const Eigen::Quaterniond q_w_b = so3::ExpQuaternion(RandomVector<3>(rng, 1.0));
    Eigen::Matrix3d A = Eigen::Matrix3d::Identity() + 0.3 * Eigen::Matrix3d::Random();
    const Eigen::Matrix3d L = (A.transpose() * A).llt().matrixU();
    const AnchoredPointFactor factor(RandomVector<3>(rng, 3.0), L);
    test::ExpectTangentJacobiansMatch(factor, {PoseBlock(p_w_b, q_w_b), PointBlock(p_w_l)}, {&pose_manifold, nullptr},
                                      1e-6);
    test::ExpectTangentEvaluationMatchesAmbient(factor, {PoseBlock(p_w_b, q_w_b), PointBlock(p_w_l)},
                                                {&pose_manifold, nullptr});
  }
}

// Stereo observations of one landmark from frames near an anchor, summarized in the anchor's body:
// the summary's information is theirs, its mean the end of their Gauss-Newton step in the point, and
// the factor built from it has their information and gradient at the linearization point, each
// divided by their count (it weighs as one observation).
TEST(AnchoredPointSummary, IsTheObservationsCostToSecondOrder) {
  RectifiedStereo stereo;  // camera = body, looking along z
  const double sigma_px = 0.7;
  const Eigen::Vector3d p_w_a(0.2, -0.1, 0.0);
  const Eigen::Quaterniond q_w_a = so3::ExpQuaternion(Eigen::Vector3d(0.05, -0.04, 0.3));
  const Eigen::Matrix3d R_w_a = q_w_a.toRotationMatrix();
  const Eigen::Vector3d p_w_l0 = p_w_a + R_w_a * Eigen::Vector3d(0.4, -0.3, 4.0);  // linearization point
  std::mt19937 rng(5);
  AnchoredPointSummary summary;
  std::vector<Eigen::Vector3d> observations;
  std::vector<std::vector<double>> frames;
  for (int k = 0; k < 6; ++k) {
    const Eigen::Vector3d p_w_f = p_w_a + Eigen::Vector3d(0.05 * k, 0.02 * k, 0.01 * k);
    const Eigen::Quaterniond q_w_f = q_w_a * so3::ExpQuaternion(Eigen::Vector3d(0.0, 0.01 * k, 0.0));
    Eigen::Vector3d z;
    ASSERT_TRUE(StereoFactor::Project(stereo, p_w_f, q_w_f, p_w_l0, &z));
    observations.push_back(z + RandomVector<3>(rng, 1.0));
    frames.push_back(PoseBlock(p_w_f, q_w_f));
    const std::vector<double> point = PointBlock(p_w_l0);
    const double* blocks[2] = {frames.back().data(), point.data()};
    Eigen::Vector3d e0;
    Eigen::Matrix<double, 3, 6, Eigen::RowMajor> J_pose;
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> J_w;
    double* jacobians[2] = {J_pose.data(), J_w.data()};
    ASSERT_TRUE(StereoFactor(observations.back(), stereo, sigma_px).EvaluateOnTangents(blocks, e0.data(), jacobians));
    summary.Add(R_w_a.transpose() * (p_w_l0 - p_w_a), e0, J_w * R_w_a);
  }
  ASSERT_TRUE(summary.Usable());
  EXPECT_EQ(summary.count(), 6);
  // The observations' Gauss-Newton step in the landmark (anchor body coordinates).
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < observations.size(); ++k) {
    const std::vector<double> point = PointBlock(p_w_l0);
    const double* blocks[2] = {frames[k].data(), point.data()};
    Eigen::Vector3d e0;
    Eigen::Matrix<double, 3, 6, Eigen::RowMajor> J_pose;
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> J_w;
    double* jacobians[2] = {J_pose.data(), J_w.data()};
    ASSERT_TRUE(StereoFactor(observations[k], stereo, sigma_px).EvaluateOnTangents(blocks, e0.data(), jacobians));
    const Eigen::Matrix3d J_a = J_w * R_w_a;
    H += J_a.transpose() * J_a;
    g += J_a.transpose() * e0;
  }
  const Eigen::Vector3d p_a0 = R_w_a.transpose() * (p_w_l0 - p_w_a);
  EXPECT_LT((summary.information() - H).norm(), 1e-9 * H.norm());
  EXPECT_LT((summary.mean() - (p_a0 - H.ldlt().solve(g))).norm(), 1e-9);
  // The factor built from the summary: gradient at p_a0 equals the observations'.
  const Eigen::Matrix3d L = summary.SqrtInformation();
  EXPECT_LT((L.transpose() * L - H / 6.0).norm(), 1e-9 * H.norm());
  const Eigen::Vector3d r0 = L * (p_a0 - summary.mean());
  EXPECT_LT((L.transpose() * r0 - g / 6.0).norm(), 1e-9 * (1.0 + g.norm()));
}

TEST(AnchoredPointSummary, NeedsFullRankInformation) {
  AnchoredPointSummary summary;
  EXPECT_FALSE(summary.Usable());
  Eigen::Matrix3d J = Eigen::Matrix3d::Zero();
  J(0, 0) = 1.0;  // one direction only
  summary.Add(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), J);
  EXPECT_FALSE(summary.Usable());
}


// A summary moved to another frame (p = R p_o + t) is the summary of its observations taken there.
TEST(AnchoredPointSummary, AbsorbMovesTheObservationsToAnotherFrame) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, -2, 0.5).normalized()).toRotationMatrix();
  const Eigen::Vector3d t(0.3, -1.2, 2.0);
  AnchoredPointSummary in_o, in_this;
  in_this.Add(Eigen::Vector3d(0.1, 0.2, 0.3), Eigen::Vector3d(0.5, -0.1, 0.2), Eigen::Matrix3d::Identity());
  AnchoredPointSummary expected = in_this;
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d p_o(1.0 + i, -0.5 * i, 4.0);
    const Eigen::Vector3d e(0.2 * i, 0.1, -0.3);
    Eigen::Matrix3d J = Eigen::Matrix3d::Identity();
    J(0, 2) = 0.1 * i;
    J(1, 0) = 0.4;
    in_o.Add(p_o, e, J);
    expected.Add(R * p_o + t, e, J * R.transpose());
  }
  in_this.Absorb(in_o, R, t);
  EXPECT_EQ(in_this.count(), 4);
  EXPECT_TRUE(in_this.information().isApprox(expected.information(), 1e-12));
  EXPECT_TRUE(in_this.mean().isApprox(expected.mean(), 1e-12));
}

}  // namespace
}  // namespace vio
