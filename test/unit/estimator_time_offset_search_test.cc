// The coarse time offset search (time_offset_search.h): a rig turning with smooth random rates, its
// gyro (biased) at 200 Hz and its camera's rotations between frames 0.4 s apart at 20 Hz (noisy, as
// a stereo 3D-3D fit is), the camera's clock `offset` ahead of the IMU's.
#include "vio/estimator/time_offset_search.h"

#include <cmath>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

namespace vio {
namespace {

// Three sinusoids per axis, about 1 rad/s.
struct Motion {
  explicit Motion(unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> frequency(0.2, 1.5), phase(0, 2 * M_PI), amplitude(0.2, 0.5);
    for (int axis = 0; axis < 3; ++axis) {
      for (int i = 0; i < 3; ++i) terms[axis][i] = {amplitude(rng), 2 * M_PI * frequency(rng), phase(rng)};
    }
  }
  Eigen::Vector3d Rate(double t) const {
    Eigen::Vector3d w;
    for (int axis = 0; axis < 3; ++axis) {
      w[axis] = 0;
      for (const Term& term : terms[axis]) w[axis] += term.a * std::sin(term.w * t + term.phi);
    }
    return w;
  }
  // The rate's exact integral from 0 to t.
  Eigen::Vector3d Angle(double t) const {
    Eigen::Vector3d angle;
    for (int axis = 0; axis < 3; ++axis) {
      angle[axis] = 0;
      for (const Term& term : terms[axis]) {
        angle[axis] += term.a / term.w * (std::cos(term.phi) - std::cos(term.w * t + term.phi));
      }
    }
    return angle;
  }
  struct Term {
    double a, w, phi;
  };
  Term terms[3][3];
};

// Feeds `seconds` of the rig to a search, the camera `offset_s` ahead (an image stamped t was taken
// at IMU time t - offset) and `applied_s` applied; returns the result.
std::optional<TimeOffsetSearch::Result> Search(double offset_s, double applied_s, double seconds, unsigned seed) {
  const Motion motion(seed);
  std::mt19937 rng(seed + 100);
  std::normal_distribution<double> camera_noise(0, 0.02), gyro_noise(0, 0.005);
  const Eigen::Vector3d bias(0.02, -0.01, 0.03);
  TimeOffsetSearch search(TimeOffsetSearch::Options{});
  const Timestamp imu_step = 5'000'000, frame_step = 50'000'000, span = 400'000'000;
  Timestamp next_frame = span;
  for (Timestamp t = 0; t <= SecondsToNanos(seconds) && !search.result(); t += imu_step) {
    const Eigen::Vector3d noise(gyro_noise(rng), gyro_noise(rng), gyro_noise(rng));
    search.AddGyro(t, motion.Rate(NanosToSeconds(t)) + bias + noise);
    // A frame stamped s (camera clock) is known to the estimator once the IMU reached its IMU time.
    while (next_frame - SecondsToNanos(applied_s) <= t) {
      const double taken0 = NanosToSeconds(next_frame - span) - offset_s, taken1 = NanosToSeconds(next_frame) - offset_s;
      const Eigen::Vector3d noise_c(camera_noise(rng), camera_noise(rng), camera_noise(rng));
      search.AddPair(next_frame - span - SecondsToNanos(applied_s), next_frame - SecondsToNanos(applied_s),
                     motion.Angle(taken1) - motion.Angle(taken0) + noise_c);
      next_frame += frame_step;
    }
  }
  return search.result();
}

TEST(TimeOffsetSearch, FindsOffsetsWithinItsRange) {
  for (const double offset_ms : {0.0, 12.0, -37.0, 62.0, -95.0}) {
    for (const unsigned seed : {1u, 2u}) {
      const auto result = Search(1e-3 * offset_ms, 0.0, 30.0, seed);
      ASSERT_TRUE(result) << offset_ms;
      EXPECT_FALSE(result->at_bound) << offset_ms;
      EXPECT_NEAR(1e3 * result->delta_s, offset_ms, 5.0) << "seed " << seed;
      EXPECT_LT(result->sigma_s, 3e-3);
      EXPECT_GE(result->pairs, TimeOffsetSearch::Options{}.decision_pairs);
    }
  }
}

TEST(TimeOffsetSearch, SearchesAroundTheAppliedOffset) {
  const auto result = Search(0.250, 0.200, 30.0, 3);
  ASSERT_TRUE(result);
  EXPECT_NEAR(1e3 * result->delta_s, 50.0, 2.0);
}

TEST(TimeOffsetSearch, AnOffsetBeyondItsRangeEndsAtTheBound) {
  const auto result = Search(0.180, 0.0, 30.0, 4);
  ASSERT_TRUE(result);
  EXPECT_TRUE(result->at_bound);
  EXPECT_NEAR(result->delta_s, 0.1, 1e-9);
  EXPECT_GT(result->improvement, 25.0);
}

TEST(TimeOffsetSearch, WithoutRotationItDoesNotDecide) {
  TimeOffsetSearch search(TimeOffsetSearch::Options{});
  for (Timestamp t = 0; t < SecondsToNanos(20.0); t += 5'000'000) {
    search.AddGyro(t, Eigen::Vector3d(0.01, 0, 0));
    if (t % 50'000'000 == 0 && t >= 600'000'000) {
      search.AddPair(t - 500'000'000, t - 100'000'000, Eigen::Vector3d::Zero());
    }
  }
  EXPECT_FALSE(search.result());
}

TEST(TimeOffsetSearch, RejectsABadRange) {
  EXPECT_THROW(TimeOffsetSearch(TimeOffsetSearch::Options{0.0, 0.001, 30, 6.0}), std::invalid_argument);
  EXPECT_THROW(TimeOffsetSearch(TimeOffsetSearch::Options{0.1, 0.2, 30, 6.0}), std::invalid_argument);
}

}  // namespace
}  // namespace vio
