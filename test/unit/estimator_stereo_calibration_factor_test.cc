// StereoCalibrationFactor: with the extrinsics alone it is StereoExtrinsicFactor to the last bit;
// with the time offset at t_d = t_a it is the reprojection; its residual is the reprojection with the
// measurement moved along the landmark's image velocity; with the time offset alone and with both
// blocks its Jacobians match central differences. ImageVelocity and its dv/dp_c against differences.
#include "vio/estimator/stereo_calibration_factor.h"

#include <random>

#include <gtest/gtest.h>

#include "estimator_test_support.h"
#include "vio/estimator/pose_manifold.h"
#include "vio/estimator/so3.h"
#include "vio/estimator/stereo_geometry.h"

namespace vio {
namespace {

using test::PoseBlock;
using test::RandomVector;

RectifiedStereo TiltedStereo() {
  RectifiedStereo stereo;
  stereo.f = 458.0;
  stereo.cx = 367.0;
  stereo.cy = 248.0;
  stereo.baseline = 0.11;
  stereo.T_b_cl.linear() = so3::Exp(Eigen::Vector3d(-1.2, 0.1, -1.2));
  stereo.T_b_cl.translation() = Eigen::Vector3d(-0.02, -0.06, 0.01);
  return stereo;
}

struct Case {
  std::vector<double> pose;
  std::vector<double> landmark;
  std::vector<double> time_offset = {0.012};
  std::vector<double> correction = {0.01, -0.02, 0.015, 0.01, -0.02, 0.005};
};

Case MakeCase(std::mt19937& rng, const RectifiedStereo& stereo) {
  const Eigen::Vector3d p_w_b = RandomVector<3>(rng, 2.0);
  const Eigen::Quaterniond q_w_b = so3::ExpQuaternion(RandomVector<3>(rng, 0.3));
  const Eigen::Vector3d p_c(RandomVector<1>(rng, 2.0)[0], RandomVector<1>(rng, 1.5)[0],
                            6.0 + RandomVector<1>(rng, 4.0)[0]);
  const Eigen::Vector3d p_w_l = p_w_b + q_w_b * (stereo.T_b_cl * p_c);
  return Case{PoseBlock(p_w_b, q_w_b), {p_w_l.x(), p_w_l.y(), p_w_l.z()}};
}

// Residual and every Jacobian of `a` and `b` on the same blocks, equal to the last bit.
void ExpectSame(const ceres::CostFunction& a, const ceres::CostFunction& b, const double* const* parameters) {
  const int n = static_cast<int>(a.parameter_block_sizes().size());
  ASSERT_EQ(n, static_cast<int>(b.parameter_block_sizes().size()));
  std::vector<std::vector<double>> ja(n), jb(n);
  std::vector<double*> pa(n), pb(n);
  for (int i = 0; i < n; ++i) {
    ja[i].assign(3 * a.parameter_block_sizes()[i], 0.0);
    jb[i].assign(3 * b.parameter_block_sizes()[i], 1.0);
    pa[i] = ja[i].data();
    pb[i] = jb[i].data();
  }
  Eigen::Vector3d ra, rb;
  ASSERT_TRUE(a.Evaluate(parameters, ra.data(), pa.data()));
  ASSERT_TRUE(b.Evaluate(parameters, rb.data(), pb.data()));
  EXPECT_EQ(ra, rb);
  for (int i = 0; i < n; ++i) EXPECT_EQ(ja[i], jb[i]) << "block " << i;
}

CameraMotion RandomMotion(std::mt19937& rng) {
  CameraMotion motion;
  motion.omega_c = test::RandomVector<3>(rng, 1.5);
  motion.v_c = test::RandomVector<3>(rng, 2.0);
  return motion;
}

Eigen::Vector3d CameraPointOf(const Case& c, const RectifiedStereo& rig) {
  const Eigen::Vector3d p_w_b(c.pose[0], c.pose[1], c.pose[2]);
  const Eigen::Quaterniond q_w_b(c.pose[6], c.pose[3], c.pose[4], c.pose[5]);
  const Eigen::Vector3d p_w_l(c.landmark[0], c.landmark[1], c.landmark[2]);
  return rig.T_b_cl.inverse() * (q_w_b.conjugate() * (p_w_l - p_w_b));
}

TEST(ImageVelocity, IsTheProjectionsRateAndItsJacobianMatchesCentralDifferences) {
  const RectifiedStereo stereo = TiltedStereo();
  std::mt19937 rng(4);
  for (int trial = 0; trial < 20; ++trial) {
    const CameraMotion motion = RandomMotion(rng);
    const Eigen::Vector3d p_c(RandomVector<1>(rng, 2.0)[0], RandomVector<1>(rng, 1.5)[0],
                              4.0 + RandomVector<1>(rng, 3.0)[0]);
    Eigen::Matrix3d d_dp_c;
    const Eigen::Vector3d v = ImageVelocity(p_c, motion, stereo, &d_dp_c);
    const double h = 1e-6;
    const Eigen::Vector3d dp_c = -motion.omega_c.cross(p_c) - motion.v_c;
    const Eigen::Vector3d rate =
        (ProjectRectified(p_c + h * dp_c, stereo) - ProjectRectified(p_c - h * dp_c, stereo)) / (2 * h);
    EXPECT_LT((v - rate).norm(), 1e-5 * (1.0 + v.norm()));
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d e = h * Eigen::Vector3d::Unit(k);
      const Eigen::Vector3d column =
          (ImageVelocity(p_c + e, motion, stereo) - ImageVelocity(p_c - e, motion, stereo)) / (2 * h);
      EXPECT_LT((d_dp_c.col(k) - column).norm(), 1e-5 * (1.0 + column.norm())) << "column " << k;
    }
  }
}

TEST(ImageVelocity, OfABodysMotionIsThatOfItsCamera) {
  // A point fixed in the world, the body turning at omega_b and moving at v_w_b: the camera
  // point's rate by finite differences of the motion equals -omega_c x p_c - v_c.
  const RectifiedStereo stereo = TiltedStereo();
  const Eigen::Quaterniond q_w_b = so3::ExpQuaternion(Eigen::Vector3d(0.2, -0.1, 0.4));
  const Eigen::Vector3d p_w_b(0.5, -1.0, 0.3), v_w_b(0.8, -0.4, 0.3), omega_b(0.3, -0.7, 0.5);
  const Eigen::Vector3d p_w_l(3.0, 1.0, -0.5);
  const auto p_c_at = [&](double t) {
    const Eigen::Quaterniond q = q_w_b * so3::ExpQuaternion(t * omega_b);
    return Eigen::Vector3d(stereo.T_b_cl.inverse() * (q.conjugate() * (p_w_l - p_w_b - t * v_w_b)));
  };
  const CameraMotion motion = CameraMotionOf(stereo, q_w_b, v_w_b, omega_b);
  const double h = 1e-6;
  const Eigen::Vector3d rate = (p_c_at(h) - p_c_at(-h)) / (2 * h);
  EXPECT_LT((rate - (-motion.omega_c.cross(p_c_at(0)) - motion.v_c)).norm(), 1e-6);
}

TEST(StereoCalibrationFactor, ResidualIsTheMeasurementMovedAlongTheLandmarksImageVelocity) {
  const RectifiedStereo stereo = TiltedStereo();
  std::mt19937 rng(5);
  Case c = MakeCase(rng, stereo);
  const Eigen::Vector3d z(300.0, 280.0, 200.0);
  const StereoCalibrationFactor::TimeOffset timing{RandomMotion(rng), 0.004};
  const StereoCalibrationFactor factor(z, stereo, 0.8, &timing, /*extrinsics=*/false);
  const StereoFactor plain(z, stereo, 0.8);
  // At t_d = t_a: the reprojection, residual and pose / landmark Jacobians to the last bit.
  c.time_offset = {0.004};
  const double* parameters[3] = {c.pose.data(), c.landmark.data(), c.time_offset.data()};
  Eigen::Vector3d r, r_plain;
  Eigen::Matrix<double, 3, 7, Eigen::RowMajor> J_pose, J_pose_plain;
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> J_landmark, J_landmark_plain;
  Eigen::Vector3d J_offset;
  double* jacobians[3] = {J_pose.data(), J_landmark.data(), J_offset.data()};
  double* jacobians_plain[2] = {J_pose_plain.data(), J_landmark_plain.data()};
  ASSERT_TRUE(factor.Evaluate(parameters, r.data(), jacobians));
  ASSERT_TRUE(plain.Evaluate(parameters, r_plain.data(), jacobians_plain));
  EXPECT_EQ(r, r_plain);
  EXPECT_EQ(J_pose, J_pose_plain);
  EXPECT_EQ(J_landmark, J_landmark_plain);
  const Eigen::Vector3d v = ImageVelocity(CameraPointOf(c, stereo), timing.motion, stereo);
  EXPECT_LT((J_offset - v / 0.8).norm(), 1e-9 * v.norm());
  // Away from it: (z + (t_d - t_a) v - h) / sigma, v at the landmark's estimate.
  c.time_offset = {0.011};
  parameters[2] = c.time_offset.data();
  ASSERT_TRUE(factor.Evaluate(parameters, r.data(), nullptr));
  EXPECT_LT((r - (r_plain + 0.007 * v / 0.8)).norm(), 1e-9 * r.norm());
}

TEST(StereoCalibrationFactor, WithTheTimeOffsetAloneJacobiansMatchCentralDifferences) {
  const RectifiedStereo stereo = TiltedStereo();
  const PoseManifold pose_manifold;
  std::mt19937 rng(8);
  for (int trial = 0; trial < 20; ++trial) {
    Case c = MakeCase(rng, stereo);
    c.time_offset = {RandomVector<1>(rng, 0.03)[0]};
    const StereoCalibrationFactor::TimeOffset timing{RandomMotion(rng), 0.003};
    const StereoCalibrationFactor factor(Eigen::Vector3d(300.0, 280.0, 200.0), stereo, 0.8, &timing, false);
    ASSERT_EQ(factor.parameter_block_sizes(), (std::vector<int32_t>{7, 3, 1}));
    const std::vector<std::vector<double>> blocks = {c.pose, c.landmark, c.time_offset};
    test::ExpectTangentJacobiansMatch(factor, blocks, {&pose_manifold, nullptr, nullptr}, 1e-6);
    test::ExpectTangentEvaluationMatchesAmbient(factor, blocks, {&pose_manifold, nullptr, nullptr});
  }
}

TEST(StereoCalibrationFactor, WithTheExtrinsicsAloneIsStereoExtrinsicFactor) {
  const RectifiedStereo stereo = TiltedStereo();
  std::mt19937 rng(6);
  const Case c = MakeCase(rng, stereo);
  const Eigen::Vector3d z(300.0, 280.0, 200.0);
  const StereoCalibrationFactor factor(z, stereo, 0.8, nullptr, /*extrinsics=*/true);
  const StereoExtrinsicFactor expected(z, stereo, 0.8);
  const double* parameters[3] = {c.pose.data(), c.landmark.data(), c.correction.data()};
  ExpectSame(factor, expected, parameters);
}

TEST(StereoCalibrationFactor, WithBothBlocksJacobiansMatchCentralDifferences) {
  const RectifiedStereo stereo = TiltedStereo();
  const PoseManifold pose_manifold;
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    Case c = MakeCase(rng, stereo);
    const Eigen::Matrix<double, 6, 1> correction = (Eigen::Matrix<double, 6, 1>() << RandomVector<3>(rng, 0.05),
                                                    RandomVector<3>(rng, 0.03)).finished();
    c.correction.assign(correction.data(), correction.data() + 6);
    c.time_offset = {RandomVector<1>(rng, 0.03)[0]};
    const StereoCalibrationFactor::TimeOffset timing{RandomMotion(rng), 0.003};
    const StereoCalibrationFactor factor(Eigen::Vector3d(300.0, 280.0, 200.0), stereo, 0.8, &timing, true);
    ASSERT_EQ(factor.parameter_block_sizes(), (std::vector<int32_t>{7, 3, 1, 6}));
    const std::vector<std::vector<double>> blocks = {c.pose, c.landmark, c.time_offset, c.correction};
    test::ExpectTangentJacobiansMatch(factor, blocks, {&pose_manifold, nullptr, nullptr, nullptr}, 1e-6);
    test::ExpectTangentEvaluationMatchesAmbient(factor, blocks, {&pose_manifold, nullptr, nullptr, nullptr});
  }
}

TEST(StereoCalibrationFactor, RejectsNonPositiveSigma) {
  EXPECT_THROW(StereoCalibrationFactor(Eigen::Vector3d::Zero(), TiltedStereo(), 0.0, nullptr, true),
               std::invalid_argument);
}

}  // namespace
}  // namespace vio
