// Dynamic initialization on analytic motions that are moving at t = 0: the
// estimator (init auto) starts within 1 s of data, by the dynamic
// initializer; the initial state (gravity direction, velocity, biases) is
// inside 3 sigma of the covariance it hands the window; the NEES over Monte
// Carlo noise draws is near its dimension; starts with no metric stereo
// motion wait and say why; a start at rest is still static.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "estimator_test_support.h"
#include "vio/estimator/dynamic_initializer.h"
#include "vio/estimator/estimator.h"
#include "vio/estimator/stereo_geometry.h"

namespace vio {
namespace {

using test::SyntheticMotion;

constexpr Timestamp kFramePeriodNs = 50'000'000;  // 20 Hz
constexpr Timestamp kImuPeriodNs = 5'000'000;     // 200 Hz
const Eigen::Vector3d kGyroBias(0.01, -0.015, 0.008);
const Eigen::Vector3d kAccelBias(0.05, -0.08, 0.06);

// Landmarks on a shell of radius [r_min, r_max] around the start, seen by
// the rectified stereo pair (body = left camera) with pixel noise.
struct StereoWorld {
  RectifiedStereo stereo;
  std::vector<Eigen::Vector3d> landmarks;

  StereoWorld(const Eigen::Vector3d& center, double r_min, double r_max, std::mt19937& rng) {
    std::normal_distribution<double> normal;
    std::uniform_real_distribution<double> radius(r_min, r_max);
    for (int i = 0; i < 3000; ++i) {
      const Eigen::Vector3d direction = Eigen::Vector3d(normal(rng), normal(rng), normal(rng)).normalized();
      landmarks.push_back(center + radius(rng) * direction);
    }
  }

  StereoFrame Observe(const test::MotionState& state, Timestamp t_ns, std::mt19937& rng) const {
    std::normal_distribution<double> pixel(0.0, 0.5);
    StereoFrame frame{t_ns, {}};
    for (size_t i = 0; i < landmarks.size(); ++i) {
      const Eigen::Vector3d p_c = state.q_w_b.conjugate() * (landmarks[i] - state.p_w_b);
      if (p_c.z() < 0.3) continue;
      Eigen::Vector3d z = ProjectRectified(p_c, stereo);
      if (z.x() < 0 || z.x() > 752 || z.y() < 0 || z.z() < 0 || z.z() > 480) continue;
      z += Eigen::Vector3d(pixel(rng), pixel(rng), pixel(rng));
      frame.observations.push_back({LandmarkId(static_cast<std::int64_t>(i)), z});
    }
    return frame;
  }
};

// IMU readings with white noise at the calibration's densities and constant biases.
std::vector<ImuSample> NoisyImu(const SyntheticMotion& motion, Timestamp last_ns, const ImuCalibration& calibration,
                                std::mt19937& rng) {
  std::normal_distribution<double> normal;
  const double dt = 1e-9 * kImuPeriodNs;
  const double gyro_sigma = calibration.gyro_noise_density / std::sqrt(dt);
  const double accel_sigma = calibration.accel_noise_density / std::sqrt(dt);
  std::vector<ImuSample> imu = motion.ImuSamples(0, last_ns, kImuPeriodNs, kGyroBias, kAccelBias);
  for (ImuSample& m : imu) {
    m.gyro_rad_s += gyro_sigma * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
    m.accel_m_s2 += accel_sigma * Eigen::Vector3d(normal(rng), normal(rng), normal(rng));
  }
  return imu;
}

struct Start {
  std::string name;
  double speed_m_s;
  double rate_rad_s;
  bool wavy;  // time-varying rate and acceleration (hand-held)
};

SyntheticMotion MotionOf(const Start& start) {
  SyntheticMotion motion = start.wavy ? SyntheticMotion::Wavy() : SyntheticMotion();
  motion.v0 = start.speed_m_s * Eigen::Vector3d(0.8, 0.5, -0.2).normalized();
  motion.w0 = start.rate_rad_s * Eigen::Vector3d(0.3, -0.4, 0.85).normalized();
  if (!start.wavy) motion.a0.setZero();
  return motion;
}

// The frames and IMU of the first `seconds` of a start.
struct Recording {
  std::vector<StereoFrame> frames;
  std::vector<ImuSample> imu;
};

Recording Record(const SyntheticMotion& motion, double seconds, double r_min, double r_max,
                 const ImuCalibration& calibration, std::uint32_t seed) {
  std::mt19937 rng(seed);
  const StereoWorld world(motion.p0, r_min, r_max, rng);
  Recording recording;
  for (Timestamp t = 0; t <= SecondsToNanos(seconds); t += kFramePeriodNs) {
    recording.frames.push_back(world.Observe(motion.At(NanosToSeconds(t)), t, rng));
  }
  recording.imu = NoisyImu(motion, SecondsToNanos(seconds) + kFramePeriodNs, calibration, rng);
  return recording;
}

// The initial state's errors in the estimate's world (yaw and position are
// the gauge: the truth is rotated about z onto the estimate) over
// [roll/pitch (world x, y), v, b_g, b_a], and their standard deviations.
struct InitError {
  Eigen::Matrix<double, 11, 1> error;
  Eigen::Matrix<double, 11, 1> sigma;
  Eigen::Matrix<double, 11, 11> covariance;
};

InitError ErrorOf(const DynamicInitResult& result, const test::MotionState& truth) {
  const InitialState& s = *result.state;
  const Eigen::Matrix3d R_offset = s.q_w_b.toRotationMatrix() * truth.q_w_b.toRotationMatrix().transpose();
  const Eigen::Matrix3d yaw(Eigen::AngleAxisd(std::atan2(R_offset(1, 0), R_offset(0, 0)), Eigen::Vector3d::UnitZ()));
  const Eigen::Matrix3d R_est = s.q_w_b.toRotationMatrix();
  const Eigen::Vector3d dtheta_w = R_est * so3::Log(Eigen::Matrix3d(R_est.transpose() * yaw * truth.q_w_b.toRotationMatrix()));
  InitError out;
  out.error << dtheta_w.head<2>(), yaw * truth.v_w_b - s.v_w_b, kGyroBias - s.gyro_bias, kAccelBias - s.accel_bias;
  Eigen::Matrix<double, 15, 15> J = Eigen::Matrix<double, 15, 15>::Identity();  // body -> world rotation
  J.block<3, 3>(3, 3) = R_est;
  const Eigen::Matrix<double, 15, 15> world = J * result.covariance * J.transpose();
  std::vector<int> index = {3, 4, 6, 7, 8, 9, 10, 11, 12, 13, 14};
  for (int i = 0; i < 11; ++i) {
    for (int j = 0; j < 11; ++j) out.covariance(i, j) = world(index[i], index[j]);
  }
  out.sigma = out.covariance.diagonal().cwiseSqrt();
  return out;
}

EstimatorOptions TestOptions() {
  EstimatorOptions options;
  options.model.imu_noise_scale = 1.0;  // the simulated noise is the calibration's
  return options;
}

std::vector<StereoFrame> FirstSeconds(const std::vector<StereoFrame>& frames, double seconds) {
  std::vector<StereoFrame> out;
  for (const StereoFrame& f : frames) {
    if (f.t_ns <= SecondsToNanos(seconds)) out.push_back(f);
  }
  return out;
}

class MovingStart : public ::testing::TestWithParam<Start> {};

TEST_P(MovingStart, InitializesWithinOneSecondInsideThreeSigma) {
  const Start start = GetParam();
  const SyntheticMotion motion = MotionOf(start);
  const EstimatorOptions options = TestOptions();
  const ImuCalibration calibration;
  const Recording recording = Record(motion, 1.0, 3.0, 8.0, calibration, 7);
  const DynamicInitResult result = InitializeDynamic(FirstSeconds(recording.frames, options.init.dynamic_window_s),
                                                     recording.imu, calibration, RectifiedStereo(), options);
  ASSERT_TRUE(result.state) << start.name << ": " << result.reason;
  const InitError e = ErrorOf(result, motion.At(NanosToSeconds(result.state->t_ns)));
  for (int i = 0; i < 11; ++i) {
    EXPECT_LE(std::abs(e.error[i]), 3 * e.sigma[i]) << start.name << " component " << i << " (tilt 2, v 3, b_g 3, "
                                                    << "b_a 3): error " << e.error[i] << ", sigma " << e.sigma[i];
  }
  EXPECT_EQ(result.earlier.size(), FirstSeconds(recording.frames, options.init.dynamic_window_s).size() - 1);

  // The estimator (init auto) starts within 1 s of data, dynamically.
  Estimator estimator(options, calibration, RectifiedStereo());
  size_t next_imu = 0;
  bool initialized = false;
  for (const StereoFrame& frame : recording.frames) {
    while (next_imu < recording.imu.size() && recording.imu[next_imu].t_ns <= frame.t_ns + kImuPeriodNs) {
      estimator.AddImu(recording.imu[next_imu++]);
    }
    if (estimator.ProcessFrame(frame).initialized) {
      initialized = true;
      break;
    }
  }
  EXPECT_TRUE(initialized) << start.name << ": " << estimator.waiting_reason();
  EXPECT_EQ(estimator.init_method(), "dynamic") << start.name;
  EXPECT_FALSE(estimator.TakeEarlierEstimates().empty()) << start.name;
}

INSTANTIATE_TEST_SUITE_P(Starts, MovingStart,
                         ::testing::Values(Start{"walk", 0.3, 0.1, true}, Start{"handheld", 0.8, 0.8, true},
                                           Start{"drone", 2.5, 0.5, false}, Start{"fast_turn", 1.0, 2.0, false},
                                           Start{"constant_velocity", 1.0, 0.0, false},
                                           Start{"pure_rotation", 0.0, 1.0, false}),
                         [](const auto& info) { return info.param.name; });

// The covariance is honest: over Monte Carlo draws of the noise (and the
// scene), the mean NEES of [tilt, v, b_g, b_a] is near its dimension (11).
TEST(DynamicInit, NeesOverMonteCarloStartsIsNearItsDimension) {
  const SyntheticMotion motion = MotionOf(Start{"handheld", 0.8, 0.8, true});
  const EstimatorOptions options = TestOptions();
  const ImuCalibration calibration;
  double nees_sum = 0;
  const int runs = 25;
  for (int run = 0; run < runs; ++run) {
    const Recording recording = Record(motion, 0.5, 3.0, 8.0, calibration, 100 + run);
    const DynamicInitResult result =
        InitializeDynamic(recording.frames, recording.imu, calibration, RectifiedStereo(), options);
    ASSERT_TRUE(result.state) << result.reason;
    const InitError e = ErrorOf(result, motion.At(NanosToSeconds(result.state->t_ns)));
    nees_sum += e.error.dot(e.covariance.ldlt().solve(e.error));
  }
  const double mean_nees = nees_sum / runs;
  // 25 runs of chi2(11): the mean is 11 +- 1.3 (1 sigma); the bounds allow a little model error.
  EXPECT_GT(mean_nees, 11 * 0.5);
  EXPECT_LT(mean_nees, 11 * 1.6);
  RecordProperty("mean_nees", std::to_string(mean_nees));
}

// Feeds a recording to an estimator until it starts; returns whether it did
// (and, in `frames`, how many frames it was given).
bool StartsWithin(const Recording& recording, Estimator* estimator, int* frames = nullptr) {
  size_t next_imu = 0;
  int given = 0;
  for (const StereoFrame& frame : recording.frames) {
    while (next_imu < recording.imu.size() && recording.imu[next_imu].t_ns <= frame.t_ns + kImuPeriodNs) {
      estimator->AddImu(recording.imu[next_imu++]);
    }
    ++given;
    if (frames != nullptr) *frames = given;
    if (estimator->ProcessFrame(frame).initialized) return true;
  }
  return false;
}

// Landmarks beyond stereo range (disparity below min_disparity_px): no metric
// motion; the IMU moves, so no static start either. It waits and says why.
TEST(DynamicInit, NoStereoDepthWaitsAndSaysWhy) {
  const SyntheticMotion motion = MotionOf(Start{"handheld", 0.8, 0.8, true});
  const ImuCalibration calibration;
  const Recording recording = Record(motion, 2.0, 150.0, 300.0, calibration, 9);
  Estimator estimator(TestOptions(), calibration, RectifiedStereo());
  EXPECT_FALSE(StartsWithin(recording, &estimator));
  EXPECT_NE(estimator.waiting_reason().find("static: the IMU is moving"), std::string::npos)
      << estimator.waiting_reason();
  EXPECT_NE(estimator.waiting_reason().find("dynamic: too few landmarks with stereo depth"), std::string::npos)
      << estimator.waiting_reason();
}

// Nothing to track at all (a blank wall, a lens cap): the same.
TEST(DynamicInit, NoFeaturesWaitsAndSaysWhy) {
  const SyntheticMotion motion = MotionOf(Start{"drone", 2.5, 0.5, false});
  const ImuCalibration calibration;
  Recording recording = Record(motion, 2.0, 3.0, 8.0, calibration, 9);
  for (StereoFrame& f : recording.frames) f.observations.clear();
  Estimator estimator(TestOptions(), calibration, RectifiedStereo());
  EXPECT_FALSE(StartsWithin(recording, &estimator));
  EXPECT_NE(estimator.waiting_reason().find("too few landmarks with stereo depth"), std::string::npos)
      << estimator.waiting_reason();
}

// --init=static on a moving start waits (the forced choice is kept), saying the IMU moves.
TEST(DynamicInit, ForcedStaticWaitsOnAMovingStart) {
  const SyntheticMotion motion = MotionOf(Start{"handheld", 0.8, 0.8, true});
  const ImuCalibration calibration;
  const Recording recording = Record(motion, 2.0, 3.0, 8.0, calibration, 9);
  EstimatorOptions options = TestOptions();
  options.init.init = "static";
  Estimator estimator(options, calibration, RectifiedStereo());
  EXPECT_FALSE(StartsWithin(recording, &estimator));
  EXPECT_NE(estimator.waiting_reason().find("the IMU is moving"), std::string::npos) << estimator.waiting_reason();
}

// At rest, auto starts as static did (after static_window_s of IMU), and the
// still frames before it get the initial pose.
TEST(DynamicInit, AtRestAutoIsStatic) {
  SyntheticMotion motion;
  motion.v0.setZero();
  motion.a0.setZero();
  motion.w0.setZero();
  const ImuCalibration calibration;
  const Recording recording = Record(motion, 2.0, 3.0, 8.0, calibration, 9);
  Estimator estimator(TestOptions(), calibration, RectifiedStereo());
  int frames = 0;
  ASSERT_TRUE(StartsWithin(recording, &estimator, &frames)) << estimator.waiting_reason();
  EXPECT_EQ(estimator.init_method(), "static");
  EXPECT_GE(frames, 18);  // static_window_s of IMU (90 % covered) first
  const std::vector<FrameEstimate> earlier = estimator.TakeEarlierEstimates();
  EXPECT_EQ(static_cast<int>(earlier.size()), frames - 1);  // every frame before, all in the still window
  EXPECT_TRUE(estimator.TakeEarlierEstimates().empty());  // handed out once
}

// A forced dynamic start at rest works too (velocity zero, gravity from the accelerometer).
TEST(DynamicInit, ForcedDynamicAtRest) {
  SyntheticMotion motion;
  motion.v0.setZero();
  motion.a0.setZero();
  motion.w0.setZero();
  const ImuCalibration calibration;
  const Recording recording = Record(motion, 1.0, 3.0, 8.0, calibration, 9);
  EstimatorOptions options = TestOptions();
  options.init.init = "dynamic";
  Estimator estimator(options, calibration, RectifiedStereo());
  ASSERT_TRUE(StartsWithin(recording, &estimator)) << estimator.waiting_reason();
  EXPECT_EQ(estimator.init_method(), "dynamic");
}

}  // namespace
}  // namespace vio
