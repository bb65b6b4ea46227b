// Alignment of an estimate onto ground truth: known motions are recovered
// exactly, posyaw leaves roll/pitch alone, names parse.
#include <cmath>
#include <stdexcept>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "vio/evaluation/trajectory_eval.h"

namespace vio::tools {
namespace {

constexpr double kPi = EIGEN_PI;

GroundTruthState Pose(Timestamp t_ns, const Eigen::Vector3d& p_w_b, const Eigen::Quaterniond& q_w_b) {
  GroundTruthState s;
  s.t_ns = t_ns;
  s.p_w_b = p_w_b;
  s.q_w_b = q_w_b;
  return s;
}

// A twisting 3D path with changing orientation, 50 ms apart.
std::vector<GroundTruthState> Helix(int n) {
  std::vector<GroundTruthState> poses;
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d p(2.0 * std::cos(0.3 * k), 1.5 * std::sin(0.3 * k),
                            0.1 * k + 0.3 * std::sin(0.7 * k));
    const Eigen::Quaterniond q(Eigen::AngleAxisd(0.2 * k, Eigen::Vector3d(0.3, 0.4, 1.0).normalized()) *
                               Eigen::AngleAxisd(0.1 * std::sin(k), Eigen::Vector3d::UnitX()));
    poses.push_back(Pose(k * 50'000'000LL, p, q));
  }
  return poses;
}

// Every pose mapped by the similarity (scale, T): p' = scale R p + t, q' = q_T q.
std::vector<GroundTruthState> Transformed(const std::vector<GroundTruthState>& poses, double scale,
                                          const Eigen::Isometry3d& T) {
  std::vector<GroundTruthState> out;
  const Eigen::Quaterniond q_T(T.linear());
  for (const GroundTruthState& s : poses) {
    out.push_back(Pose(s.t_ns, scale * (T.linear() * s.p_w_b) + T.translation(), q_T * s.q_w_b));
  }
  return out;
}

Eigen::Isometry3d MakeTransform(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

Eigen::Matrix3d Rz(double angle) {
  return Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

void ExpectIsometryNear(const Eigen::Isometry3d& actual, const Eigen::Isometry3d& expected, double tol) {
  EXPECT_LT((actual.matrix() - expected.matrix()).cwiseAbs().maxCoeff(), tol)
      << "actual\n" << actual.matrix() << "\nexpected\n" << expected.matrix();
}

TEST(EvalAlignment, IdenticalTrajectoriesGiveZeroErrorForEveryAlignment) {
  const std::vector<GroundTruthState> gt = Helix(60);
  for (Alignment a : {Alignment::kPosYaw, Alignment::kSe3, Alignment::kSim3, Alignment::kNone}) {
    EvaluationOptions options;
    options.alignment = a;
    const TrajectoryEvaluation e = EvaluateTrajectory(gt, gt, options);
    EXPECT_LT(e.ate.rmse_m, 1e-12) << AlignmentName(a);
    EXPECT_LT(e.ate.max_m, 1e-12) << AlignmentName(a);
    EXPECT_LT(e.ate.rot_rmse_deg, 1e-9) << AlignmentName(a);
    EXPECT_NEAR(e.alignment_result.scale, 1.0, 1e-12) << AlignmentName(a);
    EXPECT_EQ(e.ate.num_poses, 60);
    EXPECT_EQ(e.ate.num_skipped, 0);
  }
}

TEST(EvalAlignment, Se3RecoversAKnownRigidMotion) {
  const std::vector<GroundTruthState> gt = Helix(60);
  const Eigen::Isometry3d T_est_gt = MakeTransform(
      Eigen::AngleAxisd(1.1, Eigen::Vector3d(0.2, -0.7, 0.4).normalized()).toRotationMatrix(),
      Eigen::Vector3d(3.0, -1.0, 0.5));
  const AssociatedTrajectory pairs = Associate(Transformed(gt, 1.0, T_est_gt), gt);
  const AlignmentResult result = Align(pairs, Alignment::kSe3);
  ExpectIsometryNear(result.T_gt_est, T_est_gt.inverse(), 1e-9);
  EXPECT_EQ(result.scale, 1.0);
  const AteResult ate = ComputeAte(ApplyAlignment(pairs, result));
  EXPECT_LT(ate.rmse_m, 1e-11);
  EXPECT_LT(ate.rot_rmse_deg, 1e-9);
}

TEST(EvalAlignment, Se3RecoversTheMotionOfAPlanarPath) {
  std::vector<GroundTruthState> gt;
  for (int k = 0; k < 40; ++k) {
    const double a = 2.0 * kPi * k / 40.0;
    gt.push_back(Pose(k * 1'000'000LL, Eigen::Vector3d(std::cos(a), 2.0 * std::sin(a), 0.0),
                      Eigen::Quaterniond::Identity()));
  }
  const Eigen::Isometry3d T_est_gt = MakeTransform(
      Eigen::AngleAxisd(2.5, Eigen::Vector3d(1.0, 1.0, 0.3).normalized()).toRotationMatrix(),
      Eigen::Vector3d(-2.0, 0.3, 4.0));
  const AlignmentResult result = Align(Associate(Transformed(gt, 1.0, T_est_gt), gt), Alignment::kSe3);
  EXPECT_NEAR(result.T_gt_est.linear().determinant(), 1.0, 1e-12);
  ExpectIsometryNear(result.T_gt_est, T_est_gt.inverse(), 1e-9);
}

// A mirrored estimate x = M y (M = diag(1, 1, -1)): Sigma = C M with C the
// ground-truth covariance Q L Q^T, so U = Q, V = M Q, det(U) det(V) = -1. The
// best rotation flips the least-spread direction q3: R = (I - 2 q3 q3^T) M.
TEST(EvalAlignment, Se3NeverReturnsAReflection) {
  const std::vector<GroundTruthState> gt = Helix(60);
  std::vector<GroundTruthState> mirrored = gt;
  for (GroundTruthState& s : mirrored) s.p_w_b.z() = -s.p_w_b.z();
  const AssociatedTrajectory pairs = Associate(mirrored, gt);
  const AlignmentResult result = Align(pairs, Alignment::kSe3);

  Eigen::Matrix3Xd y(3, gt.size());
  for (size_t i = 0; i < gt.size(); ++i) y.col(i) = gt[i].p_w_b;
  y.colwise() -= y.rowwise().mean();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(y * y.transpose());
  const Eigen::Vector3d q3 = eigen.eigenvectors().col(0);  // smallest eigenvalue first
  const Eigen::Matrix3d expected =
      (Eigen::Matrix3d::Identity() - 2.0 * q3 * q3.transpose()) * Eigen::Vector3d(1, 1, -1).asDiagonal();
  EXPECT_NEAR(result.T_gt_est.linear().determinant(), 1.0, 1e-12);
  EXPECT_LT((result.T_gt_est.linear() - expected).cwiseAbs().maxCoeff(), 1e-9)
      << "got\n" << result.T_gt_est.linear() << "\nexpected\n" << expected;
}

TEST(EvalAlignment, PosYawRecoversAKnownYawAndTranslation) {
  const std::vector<GroundTruthState> gt = Helix(60);
  const Eigen::Isometry3d T_est_gt = MakeTransform(Rz(-2.4), Eigen::Vector3d(0.7, 5.0, -1.2));
  const AssociatedTrajectory pairs = Associate(Transformed(gt, 1.0, T_est_gt), gt);
  const AlignmentResult result = Align(pairs, Alignment::kPosYaw);
  ExpectIsometryNear(result.T_gt_est, T_est_gt.inverse(), 1e-9);
  const AteResult ate = ComputeAte(ApplyAlignment(pairs, result));
  EXPECT_LT(ate.rmse_m, 1e-11);
  EXPECT_LT(ate.rot_rmse_deg, 1e-9);
}

TEST(EvalAlignment, Sim3RecoversAKnownScale) {
  const std::vector<GroundTruthState> gt = Helix(60);
  const double scale_est_gt = 1.7;
  const Eigen::Isometry3d T_est_gt = MakeTransform(
      Eigen::AngleAxisd(0.6, Eigen::Vector3d(0.5, 0.1, -0.8).normalized()).toRotationMatrix(),
      Eigen::Vector3d(1.0, 2.0, 3.0));
  const AssociatedTrajectory pairs = Associate(Transformed(gt, scale_est_gt, T_est_gt), gt);
  const AlignmentResult result = Align(pairs, Alignment::kSim3);
  EXPECT_NEAR(result.scale, 1.0 / scale_est_gt, 1e-12);
  EXPECT_LT((result.T_gt_est.linear() - T_est_gt.linear().transpose()).cwiseAbs().maxCoeff(), 1e-9);
  const AteResult ate = ComputeAte(ApplyAlignment(pairs, result));
  EXPECT_LT(ate.rmse_m, 1e-11);
  EXPECT_LT(ate.rot_rmse_deg, 1e-9);
  // Without scale the error cannot vanish.
  EXPECT_GT(ComputeAte(ApplyAlignment(pairs, Align(pairs, Alignment::kSe3))).rmse_m, 0.1);
}

// Ground truth on a line through the origin along `axis` (x or y), the
// estimate = Trans(t) Rz(yaw) R_tilt ground truth, with R_tilt a roll (about
// x, line along y) or pitch (about y, line along x) of `tilt` rad. posyaw
// undoes yaw and t only: each point keeps the error |(R_tilt - I) y~_i| =
// 2 sin(tilt / 2) |y~_i| and every orientation the error angle `tilt`.
struct TiltCase {
  Eigen::Vector3d line_axis;
  Eigen::Vector3d tilt_axis;
};

class EvalPosYawTilt : public ::testing::TestWithParam<TiltCase> {};

TEST_P(EvalPosYawTilt, LeavesRollAndPitchInTheError) {
  const double tilt = 0.2;
  const double yaw = 0.9;
  std::vector<GroundTruthState> gt;
  double sum_sq_offsets = 0.0;
  for (int k = -5; k <= 5; ++k) {
    const Eigen::Quaterniond q_w_b(Eigen::AngleAxisd(0.1 * k, Eigen::Vector3d(0.3, -0.2, 1.0).normalized()));
    gt.push_back(Pose((k + 5) * 10'000'000LL, 0.5 * k * GetParam().line_axis, q_w_b));
    sum_sq_offsets += 0.25 * k * k;
  }
  const Eigen::Isometry3d T_est_gt =
      MakeTransform(Rz(yaw) * Eigen::AngleAxisd(tilt, GetParam().tilt_axis).toRotationMatrix(),
                    Eigen::Vector3d(4.0, -3.0, 2.0));
  const AssociatedTrajectory pairs = Associate(Transformed(gt, 1.0, T_est_gt), gt);
  const AlignmentResult result = Align(pairs, Alignment::kPosYaw);

  const Eigen::Matrix3d& R = result.T_gt_est.linear();
  EXPECT_LT((R.col(2) - Eigen::Vector3d::UnitZ()).norm(), 1e-12) << "roll/pitch in\n" << R;
  EXPECT_LT((R.row(2).transpose() - Eigen::Vector3d::UnitZ()).norm(), 1e-12) << "roll/pitch in\n" << R;
  EXPECT_NEAR(std::atan2(R(1, 0), R(0, 0)), -yaw, 1e-12);

  const AteResult ate = ComputeAte(ApplyAlignment(pairs, result));
  const double expected_rmse = 2.0 * std::sin(tilt / 2.0) * std::sqrt(sum_sq_offsets / 11.0);
  EXPECT_NEAR(ate.rmse_m, expected_rmse, 1e-9);
  EXPECT_NEAR(ate.max_m, 2.0 * std::sin(tilt / 2.0) * 2.5, 1e-9);
  EXPECT_NEAR(ate.rot_rmse_deg, tilt * 180.0 / kPi, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(RollAndPitch, EvalPosYawTilt,
                         ::testing::Values(TiltCase{Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitX()},
                                           TiltCase{Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY()}));

// The first-pose alignment (the estimator's gauge): the estimate is the ground
// truth moved by a known yaw and translation, its first pose also tilted and
// displaced. posyaw puts the first position on the truth and leaves a pure tilt
// (no rotation about z) in the first orientation; se3 puts the whole first pose on it.
TEST(EvalAlignment, FirstPoseAlignmentPutsTheFirstPoseOnTheTruth) {
  const std::vector<GroundTruthState> gt = Helix(20);
  const Eigen::Isometry3d T_est_gt = MakeTransform(Rz(2.2), Eigen::Vector3d(0.4, -1.0, 0.3));
  std::vector<GroundTruthState> est = Transformed(gt, 1.0, T_est_gt);
  const Eigen::Quaterniond tilt(Eigen::AngleAxisd(0.05, Eigen::Vector3d(1.0, -0.5, 0.0).normalized()));
  est.front().q_w_b = tilt * est.front().q_w_b;
  est.front().p_w_b += Eigen::Vector3d(0.02, 0.01, -0.03);
  const AssociatedTrajectory pairs = Associate(est, gt);

  const AlignmentResult posyaw = AlignAtFirstPose(pairs, Alignment::kPosYaw);
  const AssociatedTrajectory aligned = ApplyAlignment(pairs, posyaw);
  EXPECT_LT((aligned.T_w_b_est[0].translation() - gt[0].p_w_b).norm(), 1e-12);
  const Eigen::AngleAxisd error(Eigen::Matrix3d(aligned.T_w_b_gt[0].linear() * aligned.T_w_b_est[0].linear().transpose()));
  EXPECT_NEAR(error.angle(), 0.05, 1e-12);
  EXPECT_LT(std::abs(error.axis().z()), 1e-12) << "a rotation about z is left: " << error.axis().transpose();
  const Eigen::Matrix3d& R = posyaw.T_gt_est.linear();
  EXPECT_LT((R.col(2) - Eigen::Vector3d::UnitZ()).norm(), 1e-12) << "roll/pitch in\n" << R;
  // The later poses (not displaced) are off only by the first pose's displacement.
  EXPECT_LT((ApplyAlignment(pairs, AlignAtFirstPose(Associate(Transformed(gt, 1.0, T_est_gt), gt),
                                                    Alignment::kPosYaw))
                 .T_w_b_est[5]
                 .matrix() -
             aligned.T_w_b_gt[5].matrix())
                .cwiseAbs()
                .maxCoeff(),
            1e-12);

  const AssociatedTrajectory se3 = ApplyAlignment(pairs, AlignAtFirstPose(pairs, Alignment::kSe3));
  ExpectIsometryNear(se3.T_w_b_est[0], se3.T_w_b_gt[0], 1e-12);
  EXPECT_EQ(AlignAtFirstPose(pairs, Alignment::kNone).T_gt_est.matrix(), Eigen::Matrix4d::Identity());
  EXPECT_THROW(AlignAtFirstPose(AssociatedTrajectory{}, Alignment::kPosYaw), std::invalid_argument);
}

TEST(EvalAlignment, NoneIsTheIdentity) {
  const std::vector<GroundTruthState> gt = Helix(10);
  const AlignmentResult result =
      Align(Associate(Transformed(gt, 1.0, MakeTransform(Rz(0.3), Eigen::Vector3d::Ones())), gt),
            Alignment::kNone);
  EXPECT_EQ(result.T_gt_est.matrix(), Eigen::Matrix4d::Identity());
  EXPECT_EQ(result.scale, 1.0);
}

TEST(EvalAlignment, TooFewPosesIsAnError) {
  const std::vector<GroundTruthState> gt = Helix(2);
  const AssociatedTrajectory pairs = Associate(gt, gt);
  EXPECT_NO_THROW(Align(pairs, Alignment::kPosYaw));
  EXPECT_THROW(Align(pairs, Alignment::kSe3), std::invalid_argument);
  EXPECT_THROW(Align(pairs, Alignment::kSim3), std::invalid_argument);
  EXPECT_THROW(Align(AssociatedTrajectory{}, Alignment::kNone), std::invalid_argument);
}

TEST(EvalAlignment, Sim3OfAStillEstimateIsAnError) {
  std::vector<GroundTruthState> gt = Helix(5);
  std::vector<GroundTruthState> still = gt;
  for (GroundTruthState& s : still) s.p_w_b = Eigen::Vector3d(1.0, 2.0, 3.0);
  EXPECT_THROW(Align(Associate(still, gt), Alignment::kSim3), std::invalid_argument);
}

TEST(EvalAlignment, NamesRoundTripAndUnknownNamesAreRejected) {
  for (Alignment a : {Alignment::kPosYaw, Alignment::kSe3, Alignment::kSim3, Alignment::kNone}) {
    EXPECT_EQ(ParseAlignment(AlignmentName(a)), a);
  }
  try {
    ParseAlignment("yaw");
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("'yaw'"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("posyaw, se3, sim3, none"));
  }
}

}  // namespace
}  // namespace vio::tools
