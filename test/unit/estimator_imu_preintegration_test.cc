#include "vio/estimator/imu_preintegration.h"

#include <cmath>
#include <random>
#include <stdexcept>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include "estimator_test_support.h"

namespace vio {
namespace {

using test::MotionState;
using test::SyntheticMotion;

const Eigen::Vector3d kGravity(0.0, 0.0, -9.81);
const Eigen::Vector3d kTrueGyroBias(0.01, -0.02, 0.015);
const Eigen::Vector3d kTrueAccelBias(0.1, 0.05, -0.08);
constexpr Timestamp kImuPeriodNs = 5'000'000;  // 200 Hz

/// Relative motion from the ground truth: (R_i^T R_j, R_i^T(v_j - v_i - g dt),
/// R_i^T(p_j - p_i - v_i dt - g dt^2 / 2)).
ImuPreintegration::Deltas TrueDeltas(const MotionState& i, const MotionState& j, double dt) {
  ImuPreintegration::Deltas deltas;
  const Eigen::Matrix3d R_i_T = i.q_w_b.toRotationMatrix().transpose();
  deltas.delta_q = i.q_w_b.conjugate() * j.q_w_b;
  deltas.delta_v = R_i_T * (j.v_w_b - i.v_w_b - kGravity * dt);
  deltas.delta_p = R_i_T * (j.p_w_b - i.p_w_b - i.v_w_b * dt - 0.5 * kGravity * dt * dt);
  return deltas;
}

/// Largest of the rotation [rad], velocity [m/s] and position [m] errors.
double DeltasError(const ImuPreintegration::Deltas& a, const ImuPreintegration::Deltas& b) {
  return std::max({so3::Log(a.delta_q.conjugate() * b.delta_q).norm(), (a.delta_v - b.delta_v).norm(),
                   (a.delta_p - b.delta_p).norm()});
}

ImuBias TrueBias() { return ImuBias{kTrueGyroBias, kTrueAccelBias}; }

/// Preintegration of `motion` over [t0, t1] from samples every period_ns.
ImuPreintegration Preintegrate(const SyntheticMotion& motion, Timestamp t0_ns, Timestamp t1_ns,
                               Timestamp period_ns, const ImuBias& linearization_bias,
                               const ImuCalibration& calibration = ImuCalibration()) {
  const auto samples = motion.ImuSamples(0, t1_ns + period_ns, period_ns, kTrueGyroBias, kTrueAccelBias);
  return PreintegrateBetween(samples, t0_ns, t1_ns, linearization_bias, calibration);
}

// One step over an IMU gap leaves a rank-deficient covariance (the accel noise
// drives velocity and position together): Cholesky fails, and the square-root
// information must still be finite and a generalized inverse of it.
TEST(ImuPreintegration, SqrtInformationOfOneLongStepIsAFiniteGeneralizedInverse) {
  for (const double gap_s : {0.05, 0.5, 2.0, 10.0}) {
    ImuPreintegration preintegration(ImuBias{}, ImuCalibration());
    preintegration.Integrate(gap_s, Eigen::Vector3d(0.3, -0.2, 0.1), Eigen::Vector3d(0.5, 0.2, 9.81));
    const ImuPreintegration::Matrix15d S = preintegration.SqrtInformation();
    ASSERT_TRUE(S.allFinite()) << gap_s;
    const ImuPreintegration::Matrix15d& P = preintegration.covariance();
    const ImuPreintegration::Matrix15d P_W_P = P * (S.transpose() * S) * P;
    EXPECT_LT((P_W_P - P).norm(), 1e-6 * P.norm()) << gap_s;
  }
}

TEST(ImuPreintegration, ConstantRateAndAccelerationAreIntegratedExactly) {
  const SyntheticMotion motion;  // constant body rate, constant world acceleration
  const ImuPreintegration preintegration = Preintegrate(motion, 0, 1'000'000'000, kImuPeriodNs, TrueBias());
  EXPECT_EQ(preintegration.num_steps(), 200);
  EXPECT_NEAR(preintegration.delta_time_s(), 1.0, 1e-12);
  const auto expected = TrueDeltas(motion.At(0.0), motion.At(1.0), 1.0);
  EXPECT_LT(DeltasError(preintegration.deltas(), expected), 1e-10);
}

TEST(ImuPreintegration, SmoothMotionConvergesQuadraticallyInTheStep) {
  const SyntheticMotion motion = SyntheticMotion::Wavy();
  const auto expected = TrueDeltas(motion.At(0.0), motion.At(1.0), 1.0);
  const double error_200hz =
      DeltasError(Preintegrate(motion, 0, 1'000'000'000, kImuPeriodNs, TrueBias()).deltas(), expected);
  const double error_400hz =
      DeltasError(Preintegrate(motion, 0, 1'000'000'000, kImuPeriodNs / 2, TrueBias()).deltas(), expected);
  EXPECT_LT(error_200hz, 1e-4);
  EXPECT_GT(error_200hz / error_400hz, 3.5);  // second order: ratio ~4
}

TEST(ImuPreintegration, InterpolatesAtFrameTimesBetweenSamples) {
  const SyntheticMotion motion;
  // Frames 1.3 ms and 3.7 ms after an IMU sample.
  const Timestamp t0_ns = 101'300'000, t1_ns = 603'700'000;
  const ImuPreintegration preintegration = Preintegrate(motion, t0_ns, t1_ns, kImuPeriodNs, TrueBias());
  EXPECT_NEAR(preintegration.delta_time_s(), 0.5024, 1e-12);
  const double dt = NanosToSeconds(t1_ns - t0_ns);
  const auto expected = TrueDeltas(motion.At(NanosToSeconds(t0_ns)), motion.At(NanosToSeconds(t1_ns)), dt);
  // Only the linear interpolation of the rotating specific force is inexact.
  EXPECT_LT(DeltasError(preintegration.deltas(), expected), 1e-7);
}

TEST(ImuPreintegration, RejectsIntervalsTheSamplesDoNotCover) {
  const SyntheticMotion motion;
  const auto samples = motion.ImuSamples(0, 100'000'000, kImuPeriodNs, kTrueGyroBias, kTrueAccelBias);
  EXPECT_THROW(PreintegrateBetween(samples, 50'000'000, 200'000'000, TrueBias(), ImuCalibration()),
               std::invalid_argument);
  EXPECT_THROW(PreintegrateBetween(samples, 50'000'000, 50'000'000, TrueBias(), ImuCalibration()),
               std::invalid_argument);
  EXPECT_THROW(PreintegrateBetween({}, 0, 1, TrueBias(), ImuCalibration()), std::invalid_argument);
}

/// Samples of the wavy motion with irregular spacing (2..8 ms).
std::vector<ImuSample> IrregularSamples(const SyntheticMotion& motion, Timestamp last_ns) {
  std::mt19937 rng(1);
  std::uniform_int_distribution<Timestamp> period_ns(2'000'000, 8'000'000);
  std::vector<ImuSample> samples;
  for (Timestamp t = 0; t <= last_ns; t += period_ns(rng)) {
    samples.push_back(motion.Imu(t, kTrueGyroBias, kTrueAccelBias));
  }
  samples.push_back(motion.Imu(last_ns + 1'000'000, kTrueGyroBias, kTrueAccelBias));
  return samples;
}

TEST(ImuPreintegration, BiasJacobiansMatchNumericReintegration) {
  const auto samples = IrregularSamples(SyntheticMotion::Wavy(), 1'000'000'000);
  const ImuBias bias{Eigen::Vector3d(0.02, -0.01, 0.0), Eigen::Vector3d(0.05, 0.1, -0.1)};
  const ImuPreintegration nominal = PreintegrateBetween(samples, 0, 1'000'000'000, bias, ImuCalibration());
  const double h = 1e-6;
  Eigen::Matrix<double, 9, 6> numeric;  // rows [R, v, p], columns [b_g, b_a]
  for (int k = 0; k < 6; ++k) {
    ImuPreintegration plus = nominal, minus = nominal;
    ImuBias bias_plus = bias, bias_minus = bias;
    (k < 3 ? bias_plus.gyro : bias_plus.accel)[k % 3] += h;
    (k < 3 ? bias_minus.gyro : bias_minus.accel)[k % 3] -= h;
    plus.Reintegrate(bias_plus);
    minus.Reintegrate(bias_minus);
    const Eigen::Quaterniond q_inverse = nominal.deltas().delta_q.conjugate();
    numeric.block<3, 1>(0, k) = (so3::Log(q_inverse * plus.deltas().delta_q) -
                                 so3::Log(q_inverse * minus.deltas().delta_q)) / (2 * h);
    numeric.block<3, 1>(3, k) = (plus.deltas().delta_v - minus.deltas().delta_v) / (2 * h);
    numeric.block<3, 1>(6, k) = (plus.deltas().delta_p - minus.deltas().delta_p) / (2 * h);
  }
  const Eigen::Matrix3d d_delta_R_d_ba = numeric.block<3, 3>(0, 3);
  EXPECT_LT(d_delta_R_d_ba.norm(), 1e-8);  // rotation does not depend on b_a
  const auto expect_near = [](const Eigen::Matrix3d& analytic, const Eigen::Matrix3d& expected) {
    EXPECT_LT((analytic - expected).norm(), 1e-6 * expected.norm()) << analytic << "\nvs\n" << expected;
  };
  expect_near(nominal.d_delta_R_d_bg(), numeric.block<3, 3>(0, 0));
  expect_near(nominal.d_delta_v_d_bg(), numeric.block<3, 3>(3, 0));
  expect_near(nominal.d_delta_v_d_ba(), numeric.block<3, 3>(3, 3));
  expect_near(nominal.d_delta_p_d_bg(), numeric.block<3, 3>(6, 0));
  expect_near(nominal.d_delta_p_d_ba(), numeric.block<3, 3>(6, 3));
}

TEST(ImuPreintegration, FirstOrderBiasCorrectionLeavesASecondOrderError) {
  const SyntheticMotion motion = SyntheticMotion::Wavy();
  const ImuPreintegration nominal = Preintegrate(motion, 0, 1'000'000'000, kImuPeriodNs, TrueBias());
  // Errors (uncorrected, corrected) against reintegration at the bias moved by
  // `scale` times a fixed offset.
  const auto errors = [&](double scale) {
    const ImuBias moved{kTrueGyroBias + scale * Eigen::Vector3d(2e-3, -1e-3, 1e-3),
                        kTrueAccelBias + scale * Eigen::Vector3d(-1e-2, 2e-2, 1e-2)};
    ImuPreintegration reintegrated = nominal;
    reintegrated.Reintegrate(moved);
    return std::make_pair(DeltasError(nominal.deltas(), reintegrated.deltas()),
                          DeltasError(nominal.CorrectedDeltas(moved), reintegrated.deltas()));
  };
  const auto [uncorrected, corrected] = errors(1.0);
  const auto [uncorrected_half, corrected_half] = errors(0.5);
  EXPECT_GT(uncorrected, 1e-2);
  EXPECT_LT(corrected, 2e-3 * uncorrected);
  EXPECT_NEAR(uncorrected / uncorrected_half, 2.0, 0.05);  // first order
  EXPECT_NEAR(corrected / corrected_half, 4.0, 0.2);       // second order
  EXPECT_LT(DeltasError(nominal.CorrectedDeltas(TrueBias()), nominal.deltas()), 1e-15);
}

TEST(ImuPreintegration, ReintegrationEqualsAFreshIntegration) {
  const SyntheticMotion motion = SyntheticMotion::Wavy();
  const ImuBias moved{Eigen::Vector3d(0.03, 0.0, -0.02), Eigen::Vector3d(0.2, -0.1, 0.0)};
  ImuPreintegration reintegrated = Preintegrate(motion, 12'000'000, 512'000'000, kImuPeriodNs, TrueBias());
  reintegrated.Reintegrate(moved);
  const ImuPreintegration fresh = Preintegrate(motion, 12'000'000, 512'000'000, kImuPeriodNs, moved);
  EXPECT_EQ(reintegrated.num_steps(), fresh.num_steps());
  EXPECT_EQ(reintegrated.delta_time_s(), fresh.delta_time_s());
  EXPECT_LT(DeltasError(reintegrated.deltas(), fresh.deltas()), 1e-15);
  EXPECT_LT((reintegrated.covariance() - fresh.covariance()).norm(), 1e-15 * fresh.covariance().norm());
  EXPECT_LT((reintegrated.d_delta_p_d_bg() - fresh.d_delta_p_d_bg()).norm(), 1e-14);
  EXPECT_TRUE(reintegrated.linearization_bias().gyro.isApprox(moved.gyro));
}

TEST(ImuPreintegration, AppendEqualsIntegratingTheWholeInterval) {
  const SyntheticMotion motion = SyntheticMotion::Wavy();
  ImuPreintegration first = Preintegrate(motion, 3'000'000, 250'000'000, kImuPeriodNs, TrueBias());
  first.Append(Preintegrate(motion, 250'000'000, 497'000'000, kImuPeriodNs, ImuBias()));
  const ImuPreintegration whole = Preintegrate(motion, 3'000'000, 497'000'000, kImuPeriodNs, TrueBias());
  EXPECT_EQ(first.num_steps(), whole.num_steps());
  EXPECT_LT(DeltasError(first.deltas(), whole.deltas()), 1e-14);
  EXPECT_LT((first.covariance() - whole.covariance()).norm(), 1e-12 * whole.covariance().norm());
}

TEST(ImuPreintegration, RejectsAnImuThatIsNotTheBody) {
  ImuCalibration calibration;
  calibration.T_b_i.translation() = Eigen::Vector3d(0.01, 0.0, 0.0);
  EXPECT_THROW(ImuPreintegration(TrueBias(), calibration), std::invalid_argument);
}

TEST(ImuPreintegration, NeedsReintegrationComparesEachBiasWithItsThreshold) {
  const ImuPreintegration preintegration(TrueBias(), ImuCalibration());
  ImuBias bias = TrueBias();
  EXPECT_FALSE(preintegration.NeedsReintegration(bias, 1e-3, 1e-2));
  bias.gyro.z() += 2e-3;
  EXPECT_TRUE(preintegration.NeedsReintegration(bias, 1e-3, 1e-2));
  EXPECT_FALSE(preintegration.NeedsReintegration(bias, 3e-3, 1e-2));
  bias.accel.x() -= 2e-2;
  EXPECT_TRUE(preintegration.NeedsReintegration(bias, 3e-3, 1e-2));
}

TEST(ImuPreintegration, CovarianceIsPositiveDefiniteAndGrowsWithTime) {
  const SyntheticMotion motion = SyntheticMotion::Wavy();
  const ImuCalibration calibration;
  Eigen::VectorXd previous_diagonal = Eigen::VectorXd::Zero(15);
  for (const Timestamp t1_ns : {50'000'000, 200'000'000, 500'000'000, 1'000'000'000}) {
    const ImuPreintegration preintegration = Preintegrate(motion, 0, t1_ns, kImuPeriodNs, TrueBias());
    const auto& covariance = preintegration.covariance();
    EXPECT_LT((covariance - covariance.transpose()).norm(), 1e-15 * covariance.norm());
    const Eigen::SelfAdjointEigenSolver<ImuPreintegration::Matrix15d> eigen(covariance);
    EXPECT_GT(eigen.eigenvalues().minCoeff(), 0.0);
    EXPECT_TRUE((covariance.diagonal().array() > previous_diagonal.array()).all());
    previous_diagonal = covariance.diagonal();
    // Known closed forms: rotation ~ sigma_g^2 T, bias blocks = sigma_b^2 T.
    const double T = preintegration.delta_time_s();
    const double gyro_variance = calibration.gyro_noise_density * calibration.gyro_noise_density * T;
    const Eigen::Matrix3d rotation = covariance.block<3, 3>(0, 0);
    const Eigen::Matrix3d gyro_bias = covariance.block<3, 3>(9, 9);
    const Eigen::Matrix3d accel_bias = covariance.block<3, 3>(12, 12);
    const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
    EXPECT_NEAR(rotation.trace() / 3.0, gyro_variance, 0.02 * gyro_variance);
    EXPECT_TRUE(gyro_bias.isApprox(std::pow(calibration.gyro_random_walk, 2) * T * I, 1e-12));
    EXPECT_TRUE(accel_bias.isApprox(std::pow(calibration.accel_random_walk, 2) * T * I, 1e-12));
    // The whitening inverts the covariance.
    const ImuPreintegration::Matrix15d S = preintegration.SqrtInformation();
    EXPECT_LT((S.transpose() * S * covariance - ImuPreintegration::Matrix15d::Identity()).norm(), 1e-6);
  }
}

TEST(ImuPreintegration, CovarianceMatchesMonteCarloOfNoisyReadings) {
  const SyntheticMotion motion = SyntheticMotion::Wavy();
  ImuCalibration calibration;  // no bias walk: the biases stay at their true value
  calibration.gyro_random_walk = 1e-12;
  calibration.accel_random_walk = 1e-12;
  calibration.gyro_noise_density *= 20.0;  // large enough to dominate integration error
  calibration.accel_noise_density *= 20.0;
  const Timestamp t1_ns = 500'000'000;
  const auto clean = motion.ImuSamples(0, t1_ns, kImuPeriodNs, kTrueGyroBias, kTrueAccelBias);
  const ImuPreintegration reference = PreintegrateBetween(clean, 0, t1_ns, TrueBias(), calibration);
  const double sqrt_rate = std::sqrt(1e9 / static_cast<double>(kImuPeriodNs));
  std::mt19937 rng(2024);
  std::normal_distribution<double> normal;
  const int kRuns = 400;
  Eigen::Matrix<double, 9, 9> empirical = Eigen::Matrix<double, 9, 9>::Zero();
  for (int run = 0; run < kRuns; ++run) {
    auto noisy = clean;
    for (ImuSample& sample : noisy) {
      for (int k = 0; k < 3; ++k) {
        sample.gyro_rad_s[k] += calibration.gyro_noise_density * sqrt_rate * normal(rng);
        sample.accel_m_s2[k] += calibration.accel_noise_density * sqrt_rate * normal(rng);
      }
    }
    const auto deltas = PreintegrateBetween(noisy, 0, t1_ns, TrueBias(), calibration).deltas();
    Eigen::Matrix<double, 9, 1> error;
    error << so3::Log(reference.deltas().delta_q.conjugate() * deltas.delta_q),
        deltas.delta_v - reference.deltas().delta_v, deltas.delta_p - reference.deltas().delta_p;
    empirical += error * error.transpose() / kRuns;
  }
  const Eigen::Matrix<double, 9, 9> predicted = reference.covariance().topLeftCorner<9, 9>();
  for (int block = 0; block < 3; ++block) {  // rotation, velocity, position
    const double ratio = empirical.block<3, 3>(3 * block, 3 * block).trace() /
                         predicted.block<3, 3>(3 * block, 3 * block).trace();
    EXPECT_GT(ratio, 0.8) << "block " << block;
    EXPECT_LT(ratio, 1.25) << "block " << block;
  }
}

}  // namespace
}  // namespace vio
