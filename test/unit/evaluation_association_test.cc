// Association: ground truth interpolated at estimate stamps (linear position,
// slerp rotation), stamps outside the span or inside gaps counted as skipped.
#include <cmath>
#include <stdexcept>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "vio/evaluation/trajectory_eval.h"

namespace vio::tools {
namespace {

constexpr double kPi = EIGEN_PI;
constexpr Timestamp kT0 = 10'000'000'000;  // first ground-truth stamp [ns]
constexpr Timestamp kStep = 100'000'000;   // ground-truth spacing [ns]

GroundTruthState Pose(Timestamp t_ns, const Eigen::Vector3d& p_w_b, double yaw_rad) {
  GroundTruthState s;
  s.t_ns = t_ns;
  s.p_w_b = p_w_b;
  s.q_w_b = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ());
  return s;
}

// Samples k = 0..3 at 10 s + k 0.1 s: position (k, 2k, -k) [m], yaw k 90 deg.
std::vector<GroundTruthState> GroundTruth() {
  std::vector<GroundTruthState> gt;
  for (int k = 0; k < 4; ++k) {
    gt.push_back(Pose(kT0 + k * kStep, Eigen::Vector3d(k, 2.0 * k, -k), k * kPi / 2));
  }
  return gt;
}

double YawOf(const Eigen::Isometry3d& T) { return std::atan2(T.linear()(1, 0), T.linear()(0, 0)); }

TEST(EvalAssociation, InterpolatesPositionLinearlyAndRotationBySlerp) {
  const std::vector<GroundTruthState> est = {
      Pose(kT0 + kStep / 4, Eigen::Vector3d(7, 8, 9), 0.3),
      Pose(kT0 + 2 * kStep + 3 * kStep / 5, Eigen::Vector3d::Zero(), 0.0)};
  const AssociatedTrajectory pairs = Associate(est, GroundTruth());
  ASSERT_EQ(pairs.t_ns.size(), 2u);
  EXPECT_EQ(pairs.num_skipped, 0);
  EXPECT_LT((pairs.T_w_b_gt[0].translation() - Eigen::Vector3d(0.25, 0.5, -0.25)).norm(), 1e-12);
  EXPECT_NEAR(YawOf(pairs.T_w_b_gt[0]), kPi / 8, 1e-12);
  EXPECT_LT((pairs.T_w_b_gt[1].translation() - Eigen::Vector3d(2.6, 5.2, -2.6)).norm(), 1e-12);
  EXPECT_NEAR(YawOf(pairs.T_w_b_gt[1]), -kPi + 0.6 * kPi / 2, 1e-12);  // 180 deg + 54 deg, wrapped
  EXPECT_LT(pairs.T_w_b_gt[0].linear().col(2).head<2>().norm(), 1e-12);
  // The estimate is kept as given.
  EXPECT_EQ(pairs.t_ns[0], est[0].t_ns);
  EXPECT_EQ(pairs.T_w_b_est[0].translation(), Eigen::Vector3d(7, 8, 9));
  EXPECT_NEAR(YawOf(pairs.T_w_b_est[0]), 0.3, 1e-12);
}

TEST(EvalAssociation, StampsOnSamplesTakeThemExactly) {
  const std::vector<GroundTruthState> gt = GroundTruth();
  const AssociatedTrajectory pairs = Associate(gt, gt);
  ASSERT_EQ(pairs.t_ns.size(), gt.size());
  for (size_t k = 0; k < gt.size(); ++k) {
    EXPECT_EQ((pairs.T_w_b_gt[k].translation() - gt[k].p_w_b).norm(), 0.0);
    EXPECT_LT((pairs.T_w_b_gt[k].linear() - gt[k].q_w_b.toRotationMatrix()).norm(), 1e-15);
  }
}

TEST(EvalAssociation, StampsOutsideTheSpanAreCountedNotSilentlyDropped) {
  AssociationOptions options;
  options.tolerance_ns = 1'000'000;
  const Timestamp first = kT0;
  const Timestamp last = kT0 + 3 * kStep;
  const std::vector<GroundTruthState> est = {
      Pose(first - 50 * kStep, Eigen::Vector3d::Zero(), 0.0),    // far before: skipped
      Pose(first - 2'000'000, Eigen::Vector3d::Zero(), 0.0),      // 2 ms before: skipped
      Pose(first - 500'000, Eigen::Vector3d::Zero(), 0.0),        // 0.5 ms before: first sample
      Pose(first + kStep / 2, Eigen::Vector3d::Zero(), 0.0),    // inside
      Pose(last + 1'000'000, Eigen::Vector3d::Zero(), 0.0),       // 1 ms after: last sample
      Pose(last + 1'000'001, Eigen::Vector3d::Zero(), 0.0),       // beyond the tolerance: skipped
  };
  const AssociatedTrajectory pairs = Associate(est, GroundTruth(), options);
  EXPECT_EQ(pairs.num_skipped, 3);
  ASSERT_EQ(pairs.t_ns.size(), 3u);
  EXPECT_EQ(pairs.t_ns[0], first - 500'000);
  EXPECT_EQ(pairs.T_w_b_gt[0].translation(), Eigen::Vector3d(0, 0, 0));
  EXPECT_EQ(pairs.T_w_b_gt[2].translation(), Eigen::Vector3d(3, 6, -3));
  EXPECT_EQ(ComputeAte(pairs).num_skipped, 3);
  EXPECT_EQ(Associate(est, {}, options).num_skipped, 6);
}

TEST(EvalAssociation, GroundTruthGapsAreNotInterpolatedAcross) {
  std::vector<GroundTruthState> gt = GroundTruth();
  const Timestamp after_gap = kT0 + 3 * kStep + 10 * kStep;
  gt.push_back(Pose(after_gap, Eigen::Vector3d::Zero(), 0.0));
  AssociationOptions options;
  options.max_gap_ns = 5 * kStep;
  const std::vector<GroundTruthState> est = {Pose(kT0 + 2 * kStep, Eigen::Vector3d::Zero(), 0.0),
                                             Pose(after_gap - kStep, Eigen::Vector3d::Zero(), 0.0),
                                             Pose(after_gap, Eigen::Vector3d::Zero(), 0.0)};
  const AssociatedTrajectory pairs = Associate(est, gt, options);
  EXPECT_EQ(pairs.num_skipped, 1);
  EXPECT_THAT(pairs.t_ns, ::testing::ElementsAre(kT0 + 2 * kStep, after_gap));
  options.max_gap_ns = 10 * kStep;  // the gap itself is allowed
  EXPECT_EQ(Associate(est, gt, options).num_skipped, 0);
}

// By default a gap is 10 median intervals: a 200 Hz ground truth is not
// interpolated across 0.2 s, one at 10 Hz still is across 0.2 s.
TEST(EvalAssociation, DefaultGapIsTenMedianIntervals) {
  for (const Timestamp period : {Timestamp{5'000'000}, Timestamp{100'000'000}}) {
    std::vector<GroundTruthState> gt;
    for (int k = 0; k < 40; ++k) gt.push_back(Pose(kT0 + k * period, Eigen::Vector3d(k, 0, 0), 0.0));
    const Timestamp hole_start = gt.back().t_ns;
    gt.push_back(Pose(hole_start + 200'000'000, Eigen::Vector3d(50, 0, 0), 0.0));
    const std::vector<GroundTruthState> est = {Pose(hole_start + 100'000'000, Eigen::Vector3d::Zero(), 0.0)};
    EXPECT_EQ(Associate(est, gt).num_skipped, period == 5'000'000 ? 1 : 0) << period;
  }
}

TEST(EvalAssociation, StampsMustIncrease) {
  const std::vector<GroundTruthState> gt = GroundTruth();
  std::vector<GroundTruthState> est = {gt[1], gt[0]};
  try {
    Associate(est, gt);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("estimate stamps are not strictly increasing: pose 1"));
  }
  std::vector<GroundTruthState> repeated = gt;
  repeated[2].t_ns = repeated[1].t_ns;
  EXPECT_THROW(Associate(gt, repeated), std::invalid_argument);
}

}  // namespace
}  // namespace vio::tools
