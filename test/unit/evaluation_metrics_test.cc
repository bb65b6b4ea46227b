// ATE statistics and RPE against analytic values: known per-pose errors, a
// known scale drift and a known rotation-rate drift on a straight line.
#include <cmath>
#include <stdexcept>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "vio/evaluation/trajectory_eval.h"

namespace vio::tools {
namespace {

constexpr double kPi = EIGEN_PI;
constexpr Timestamp kStepNs = 250'000'000;  // 4 Hz
constexpr double kStepM = 0.25;             // at 1 m/s: exact in binary

GroundTruthState Pose(Timestamp t_ns, const Eigen::Vector3d& p_w_b, const Eigen::Quaterniond& q_w_b) {
  GroundTruthState s;
  s.t_ns = t_ns;
  s.p_w_b = p_w_b;
  s.q_w_b = q_w_b;
  return s;
}

// Along +x at 1 m/s, level, for `n` samples 0.25 m apart.
std::vector<GroundTruthState> StraightLine(int n) {
  std::vector<GroundTruthState> poses;
  for (int k = 0; k < n; ++k) {
    poses.push_back(Pose(k * kStepNs, Eigen::Vector3d(k * kStepM, 0.0, 0.0), Eigen::Quaterniond::Identity()));
  }
  return poses;
}

TEST(EvalAte, StatisticsOfKnownPositionErrors) {
  const std::vector<GroundTruthState> gt = StraightLine(4);
  std::vector<GroundTruthState> est = gt;
  est[0].p_w_b += Eigen::Vector3d(1.0, 0.0, 0.0);
  est[1].p_w_b += Eigen::Vector3d(0.0, -2.0, 0.0);
  est[2].p_w_b += Eigen::Vector3d(0.0, 0.0, 4.0);
  est[3].p_w_b += Eigen::Vector3d(1.8, 0.0, 2.4);  // |.| = 3
  est[1].q_w_b = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
  const AteResult ate = ComputeAte(Associate(est, gt));
  EXPECT_NEAR(ate.rmse_m, std::sqrt((1.0 + 4.0 + 16.0 + 9.0) / 4.0), 1e-12);
  EXPECT_NEAR(ate.mean_m, 2.5, 1e-12);
  EXPECT_NEAR(ate.median_m, 2.5, 1e-12);
  EXPECT_NEAR(ate.max_m, 4.0, 1e-12);
  EXPECT_NEAR(ate.rot_rmse_deg, 0.3 * 180.0 / kPi / 2.0, 1e-9);  // sqrt(0.3^2 / 4)
  EXPECT_EQ(ate.num_poses, 4);
  EXPECT_THROW(ComputeAte(AssociatedTrajectory{}), std::invalid_argument);
}

// Estimate positions (1 + k) p: over every pair |t(E)| = k L exactly.
TEST(EvalRpe, ScaleDriftGivesItsPercentage) {
  const int n = 81;  // 20 m
  const double k = 0.02;
  const std::vector<GroundTruthState> gt = StraightLine(n);
  std::vector<GroundTruthState> est = gt;
  for (GroundTruthState& s : est) s.p_w_b *= 1.0 + k;
  const std::vector<RpeResult> rpe = ComputeRpe(Associate(est, gt), {1, 2, 5, 10, 20, 100});
  ASSERT_EQ(rpe.size(), 6u);
  for (int m = 0; m < 5; ++m) {
    const RpeResult& r = rpe[m];
    SCOPED_TRACE(r.length_m);
    EXPECT_NEAR(r.trans_pct, k * 100.0, 1e-9);
    EXPECT_NEAR(r.rot_deg_per_m, 0.0, 1e-12);
    EXPECT_EQ(r.num_pairs, n - static_cast<int>(r.length_m / kStepM));
  }
  EXPECT_EQ(rpe[5].length_m, 100.0);
  EXPECT_EQ(rpe[5].num_pairs, 0);
  EXPECT_TRUE(std::isnan(rpe[5].trans_pct));
  EXPECT_TRUE(std::isnan(rpe[5].rot_deg_per_m));
}

// Estimate orientation Rz(w t) on the ground-truth positions: R(E) = Rz(w L)
// for every pair, so rot = w [deg/s] / 1 m/s; t(E) = Rz(-w t_i) d - d with
// |.| = 2 |sin(w t_i / 2)| L.
TEST(EvalRpe, RotationRateDriftGivesItsDegreesPerMetre) {
  const int n = 81;
  const double rate_deg_s = 0.5;
  const double rate_rad_s = rate_deg_s * kPi / 180.0;
  const std::vector<GroundTruthState> gt = StraightLine(n);
  std::vector<GroundTruthState> est = gt;
  for (GroundTruthState& s : est) {
    s.q_w_b = Eigen::AngleAxisd(rate_rad_s * NanosToSeconds(s.t_ns), Eigen::Vector3d::UnitZ());
  }
  for (const RpeResult& r : ComputeRpe(Associate(est, gt), {1, 2, 5, 10})) {
    SCOPED_TRACE(r.length_m);
    EXPECT_NEAR(r.rot_deg_per_m, rate_deg_s, 1e-9);
    double sum_trans_m = 0.0;
    for (int i = 0; i < r.num_pairs; ++i) {
      sum_trans_m += 2.0 * std::abs(std::sin(rate_rad_s * i * kStepM / 2.0)) * r.length_m;
    }
    EXPECT_NEAR(r.trans_pct, sum_trans_m / r.num_pairs / r.length_m * 100.0, 1e-9);
  }
}

// Sub-trajectories are measured along the ground truth, not the estimate.
TEST(EvalRpe, LengthIsTravelledGroundTruthDistance) {
  std::vector<GroundTruthState> gt;  // a 1 m x 1 m square walked at 0.25 m steps: 4 m, ends at start
  const Eigen::Vector3d corners[] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 0}};
  for (int side = 0; side < 4; ++side) {
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d p = corners[side] + 0.25 * k * (corners[side + 1] - corners[side]);
      gt.push_back(Pose(static_cast<Timestamp>(gt.size()) * kStepNs, p, Eigen::Quaterniond::Identity()));
    }
  }
  gt.push_back(Pose(16 * kStepNs, corners[4], Eigen::Quaterniond::Identity()));
  const std::vector<RpeResult> rpe = ComputeRpe(Associate(gt, gt), {2, 4, 4.25});
  EXPECT_EQ(rpe[0].num_pairs, 17 - 8);
  EXPECT_EQ(rpe[1].num_pairs, 1);  // start to end: 4 m travelled, 0 m apart
  EXPECT_EQ(rpe[2].num_pairs, 0);
  EXPECT_NEAR(rpe[1].trans_pct, 0.0, 1e-12);
}

TEST(EvalRpe, NonPositiveLengthIsAnError) {
  const AssociatedTrajectory pairs = Associate(StraightLine(5), StraightLine(5));
  EXPECT_THROW(ComputeRpe(pairs, {1.0, 0.0}), std::invalid_argument);
  EXPECT_THROW(ComputeRpe(pairs, {-2.0}), std::invalid_argument);
}

// A globally scaled estimate: sim3 alignment removes the scale from RPE too.
// (An L-shaped path: a straight line would leave the roll about it free.)
TEST(EvalEvaluate, Sim3AlignmentAppliesBeforeRpe) {
  std::vector<GroundTruthState> gt = StraightLine(41);
  for (size_t k = 20; k < gt.size(); ++k) {
    gt[k].p_w_b = Eigen::Vector3d(20 * kStepM, (static_cast<double>(k) - 20.0) * kStepM, 0.0);
  }
  std::vector<GroundTruthState> est = gt;
  for (GroundTruthState& s : est) s.p_w_b *= 3.0;
  EvaluationOptions options;
  options.alignment = Alignment::kSim3;
  options.rpe_lengths_m = {1, 2};
  const TrajectoryEvaluation e = EvaluateTrajectory(est, gt, options);
  EXPECT_NEAR(e.alignment_result.scale, 1.0 / 3.0, 1e-12);
  EXPECT_LT(e.ate.rmse_m, 1e-12);
  for (const RpeResult& r : e.rpe) EXPECT_NEAR(r.trans_pct, 0.0, 1e-9);
  // Without scale: E = (I, 3 d - d) for d = p_j - p_i, |d| = L except across the corner.
  options.alignment = Alignment::kSe3;
  const RpeResult se3_1m = EvaluateTrajectory(est, gt, options).rpe[0];
  double sum_trans_m = 0.0;
  for (size_t i = 0; i + 4 < gt.size(); ++i) sum_trans_m += 2.0 * (gt[i + 4].p_w_b - gt[i].p_w_b).norm();
  EXPECT_EQ(se3_1m.num_pairs, 37);
  EXPECT_NEAR(se3_1m.trans_pct, sum_trans_m / 37.0 * 100.0, 1e-9);
}

TEST(EvalEvaluate, NoOverlapIsAnErrorNamingTheSpans) {
  const std::vector<GroundTruthState> gt = StraightLine(5);
  std::vector<GroundTruthState> est = gt;
  for (GroundTruthState& s : est) s.t_ns += 10 * kStepNs;
  try {
    EvaluateTrajectory(est, gt);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("none of the 5 estimate poses"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("[0, 1000000000] ns"));
  }
}

}  // namespace
}  // namespace vio::tools
