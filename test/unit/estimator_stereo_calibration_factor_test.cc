// StereoCalibrationFactor: with one calibration block it is that block's factor (time offset:
// StereoTimeOffsetFactor, extrinsics: StereoExtrinsicFactor) to the last bit; with both, its
// Jacobians match central differences.
#include "vio/estimator/stereo_calibration_factor.h"

#include <random>

#include <gtest/gtest.h>

#include "estimator_test_support.h"
#include "vio/estimator/pose_manifold.h"
#include "vio/estimator/so3.h"
#include "vio/estimator/stereo_time_offset_factor.h"

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

TEST(StereoCalibrationFactor, WithTheTimeOffsetAloneIsStereoTimeOffsetFactor) {
  const RectifiedStereo stereo = TiltedStereo();
  std::mt19937 rng(5);
  const Case c = MakeCase(rng, stereo);
  const Eigen::Vector3d z(300.0, 280.0, 200.0), v(40.0, 35.0, -12.0);
  const StereoCalibrationFactor::TimeOffset timing{v, 0.004};
  const StereoCalibrationFactor factor(z, stereo, 0.8, &timing, /*extrinsics=*/false);
  const StereoTimeOffsetFactor expected(z, v, 0.004, stereo, 0.8);
  const double* parameters[3] = {c.pose.data(), c.landmark.data(), c.time_offset.data()};
  ExpectSame(factor, expected, parameters);
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
    const StereoCalibrationFactor::TimeOffset timing{RandomVector<3>(rng, 50.0), 0.003};
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
