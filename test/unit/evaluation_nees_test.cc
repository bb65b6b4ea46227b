// NEES against analytic values: a known error and covariance through an
// SE3 alignment (the world-frame position block turns, the body-frame
// rotation block does not), covariance.csv parsing and its errors, and the
// chi-square bounds against tabulated quantiles.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/dataset/euroc_dataset.h"
#include "vio/estimator/so3.h"
#include "vio/evaluation/nees.h"

namespace vio::tools {
namespace {

using ::testing::HasSubstr;

Eigen::Isometry3d Pose(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.toRotationMatrix();
  T.translation() = p;
  return T;
}

TEST(Nees, KnownErrorThroughAnAlignmentEqualsTheQuadraticForm) {
  // Covariance in the estimate's world: anisotropic position, correlated rotation.
  Eigen::Matrix<double, 6, 6> sigma = Eigen::Matrix<double, 6, 6>::Zero();
  sigma.topLeftCorner<3, 3>() = Eigen::Vector3d(1e-4, 4e-4, 9e-4).asDiagonal();
  sigma.bottomRightCorner<3, 3>() = Eigen::Vector3d(1e-6, 2e-6, 3e-6).asDiagonal();
  sigma(0, 3) = sigma(3, 0) = 5e-6;
  // Estimate and truth in the estimate's world; the error there is known.
  const Eigen::Isometry3d est =
      Pose(Eigen::Vector3d(1, 2, 3), Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitY())));
  Eigen::Matrix<double, 6, 1> e;
  e << 0.01, -0.02, 0.03, 1e-3, -2e-3, 1.5e-3;
  const Eigen::Isometry3d truth =
      Pose(est.translation() + e.head<3>(), Eigen::Quaterniond(est.linear()) * so3::ExpQuaternion(e.tail<3>()));
  // The ground truth's world is the estimate's turned by 1 rad of yaw and moved.
  AlignmentResult alignment;
  alignment.T_gt_est =
      Pose(Eigen::Vector3d(5, -1, 2), Eigen::Quaterniond(Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ())));
  AssociatedTrajectory aligned;
  aligned.t_ns = {100};
  aligned.T_w_b_est = {alignment.T_gt_est * est};
  aligned.T_w_b_gt = {alignment.T_gt_est * truth};

  const NeesResult nees = ComputeNees(aligned, alignment, {{100, sigma}, {200, sigma}});
  ASSERT_EQ(nees.samples.size(), 1u);
  const double expected_pose = e.dot(sigma.llt().solve(e));
  const double expected_position = e.head<3>().dot(sigma.topLeftCorner<3, 3>().llt().solve(e.head<3>()));
  const double expected_orientation = e.tail<3>().dot(sigma.bottomRightCorner<3, 3>().llt().solve(e.tail<3>()));
  EXPECT_NEAR(nees.samples[0].pose, expected_pose, 1e-9 * expected_pose);
  EXPECT_NEAR(nees.samples[0].position, expected_position, 1e-9 * expected_position);
  EXPECT_NEAR(nees.samples[0].orientation, expected_orientation, 1e-6 * expected_orientation);
  EXPECT_DOUBLE_EQ(nees.mean_pose, nees.samples[0].pose);
  // Without turning the covariance with the alignment the numbers differ.
  AlignmentResult unturned;
  unturned.T_gt_est = Pose(Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity());
  EXPECT_GT(std::abs(ComputeNees(aligned, unturned, {{100, sigma}}).samples[0].position - expected_position),
            0.1 * expected_position);
}

TEST(Nees, FramesWithoutCovarianceAreCounted) {
  AssociatedTrajectory aligned;
  aligned.t_ns = {1, 2};
  aligned.T_w_b_est = {Eigen::Isometry3d::Identity(), Eigen::Isometry3d::Identity()};
  aligned.T_w_b_gt = aligned.T_w_b_est;
  const NeesResult nees =
      ComputeNees(aligned, AlignmentResult(), {{2, Eigen::Matrix<double, 6, 6>::Identity()}});
  EXPECT_EQ(nees.samples.size(), 1u);
  EXPECT_EQ(nees.num_without_covariance, 1);
  EXPECT_EQ(nees.samples[0].pose, 0.0);
}

std::string WriteCsv(const std::string& name, const std::string& rows) {
  const std::string path = test::MakeTempDir("nees") + "/" + name;
  std::ofstream(path) << "#t_ns,pose_0_0,...\n" << rows;
  return path;
}

std::string Row(Timestamp t_ns, double variance) {
  std::string row = std::to_string(t_ns);
  for (int r = 0; r < 6; ++r) {
    for (int c = r; c < 6; ++c) row += r == c ? "," + std::to_string(variance) : ",0";
  }
  for (int k = 0; k < 9; ++k) row += ",1";
  return row + "\n";
}

TEST(Nees, ReadsCovarianceCsv) {
  const std::vector<PoseCovariance> rows = ReadCovarianceCsv(WriteCsv("ok.csv", Row(10, 0.5) + Row(20, 2.0)));
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_EQ(rows[1].t_ns, 20);
  const Eigen::Matrix<double, 6, 6> expected = Eigen::Matrix<double, 6, 6>::Identity() * 2.0;
  EXPECT_TRUE(rows[1].pose == expected) << rows[1].pose;
}

TEST(Nees, BadCovarianceCsvNamesFileAndLine) {
  const auto message = [](const std::string& rows) {
    try {
      ReadCovarianceCsv(WriteCsv("bad.csv", rows));
    } catch (const DatasetError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_THAT(message(Row(10, 1) + "20,1,2\n"), HasSubstr("bad.csv:3: 3 columns, expected 31"));
  EXPECT_THAT(message(Row(10, 1) + Row(10, 1)), HasSubstr("bad.csv:3: timestamp 10 does not increase"));
  EXPECT_THAT(message(Row(10, -1)), HasSubstr("bad.csv:2: the pose covariance is not positive definite"));
  EXPECT_THAT(message("abc" + Row(10, 1).substr(2)), HasSubstr("bad.csv:2: 'abc"));
  EXPECT_THAT(message(Row(10, 1).substr(0, 5) + ",nan" + Row(10, 1).substr(5)), HasSubstr("finite number"));
}

TEST(Nees, ChiSquareBoundsMatchTabulatedQuantiles) {
  // chi2(120): 2.5% 91.5726, 97.5% 152.2114 (20 runs of 6 dof).
  const ChiSquareBounds twenty = AneesBounds95(6, 20);
  EXPECT_NEAR(twenty.lower, 91.5726 / 20, 1e-3 * 91.5726 / 20);
  EXPECT_NEAR(twenty.upper, 152.2114 / 20, 1e-3 * 152.2114 / 20);
  // chi2(6): 2.5% 1.2373, 97.5% 14.4494 (one run): the approximation is coarser at few dof.
  const ChiSquareBounds one = AneesBounds95(6, 1);
  EXPECT_NEAR(one.lower, 1.2373, 0.03 * 1.2373);
  EXPECT_NEAR(one.upper, 14.4494, 0.01 * 14.4494);
}

}  // namespace
}  // namespace vio::tools
