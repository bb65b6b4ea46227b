// The rig rotation search (rig_rotation_search.h): synthetic frame pairs whose gyro rotations are
// the camera's turned by a known rig error, with a gyro bias, the camera's rotations shrunk along
// some axes and noise; the fit recovers the turn, and a motion about one axis is not enough.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "vio/estimator/rig_rotation_search.h"
#include "vio/estimator/so3.h"

namespace vio {
namespace {

constexpr double kDeg = M_PI / 180.0;

struct Pairs {
  Eigen::Matrix3d Q;
  Eigen::Vector3d bias;
  Eigen::Matrix3d shrink = Eigen::Matrix3d::Identity();  // the camera's rotations, measured
  double noise_rad = 0.0;
  bool one_axis = false;
};

// Feeds `n` pairs; returns the search.
RigRotationSearch Feed(const Pairs& p, int n, RigRotationSearch::Options options = {}) {
  RigRotationSearch search(options);
  std::mt19937 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d theta(normal(rng), normal(rng), normal(rng));
    if (p.one_axis) theta = Eigen::Vector3d(0, 0, 1) * (1.0 + 0.2 * normal(rng));
    theta *= 0.3;
    const double dt = 0.5 + 0.01 * (i % 10);
    const Eigen::Vector3d noise(normal(rng), normal(rng), normal(rng));
    search.AddPair(p.Q * theta + p.bias * dt, p.shrink * theta + p.noise_rad * noise, dt);
  }
  return search;
}

double AngleDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) { return so3::Log(Eigen::Matrix3d(a * b.transpose())).norm() / kDeg; }

TEST(RigRotationSearch, RecoversTheTurnAndTheBiasWithoutNoise) {
  Pairs p;
  p.Q = so3::Exp(Eigen::Vector3d(1.0, -2.0, 0.5).normalized() * 5.0 * kDeg);
  p.bias = Eigen::Vector3d(0.01, -0.02, 0.005);
  const RigRotationSearch search = Feed(p, 150);
  ASSERT_TRUE(search.result().has_value());
  EXPECT_LT(AngleDeg(search.result()->Q, p.Q), 1e-8);
  EXPECT_LT((search.result()->gyro_bias - p.bias).norm(), 1e-10);
  EXPECT_NEAR(search.result()->rotation_vector.norm(), 5.0 * kDeg, 1e-10);
  EXPECT_LT(search.result()->sigma_rad, 1e-8);
}

TEST(RigRotationSearch, TheCamerasShrunkRotationsLeaveTheTurn) {
  // The 3D-3D fits shrink the rotation about some axes (a symmetric factor): the polar factor of
  // the linear fit is the turn; a rotation-only fit would be pulled off by it.
  Pairs p;
  p.Q = so3::Exp(Eigen::Vector3d(0.0, 1.0, 1.0).normalized() * 3.0 * kDeg);
  p.bias = Eigen::Vector3d::Zero();
  const Eigen::Matrix3d axes = so3::Exp(Eigen::Vector3d(0.3, 0.2, -0.4));
  p.shrink = axes * Eigen::Vector3d(0.9, 0.97, 1.0).asDiagonal() * axes.transpose();
  const RigRotationSearch search = Feed(p, 150);
  ASSERT_TRUE(search.result().has_value());
  EXPECT_LT(AngleDeg(search.result()->Q, p.Q), 1e-8);
}

TEST(RigRotationSearch, NoisyPairsGiveTheTurnWithinItsSigma) {
  Pairs p;
  p.Q = so3::Exp(Eigen::Vector3d(-1.0, 0.2, 0.1).normalized() * 5.0 * kDeg);
  p.bias = Eigen::Vector3d(0.003, 0.0, -0.004);
  p.noise_rad = 0.01;
  RigRotationSearch::Options options;
  options.decision_sigma_rad = 0.002;
  const RigRotationSearch search = Feed(p, 400, options);
  ASSERT_TRUE(search.result().has_value());
  const double error_deg = AngleDeg(search.result()->Q, p.Q);
  EXPECT_GT(search.result()->sigma_rad, 0.0);
  EXPECT_LT(error_deg, 4.0 * search.result()->sigma_rad / kDeg);
  EXPECT_LT(error_deg, 0.2);
}

TEST(RigRotationSearch, WaitsForEnoughPairsAndRotation) {
  Pairs p;
  p.Q = Eigen::Matrix3d::Identity();
  p.bias = Eigen::Vector3d::Zero();
  RigRotationSearch search = Feed(p, 99);
  EXPECT_FALSE(search.result().has_value());
  EXPECT_TRUE(search.Fit().sigma_rad < 1e-8);  // the pairs so far fit, but too few to decide
  EXPECT_FALSE(search.Decide().has_value());
  RigRotationSearch small;
  small.AddPair(Eigen::Vector3d(0.05, 0, 0), Eigen::Vector3d(0.05, 0, 0), 0.5);  // below min_pair_rotation_rad
  EXPECT_EQ(small.Fit().pairs, 0);
}

TEST(RigRotationSearch, ARotationAboutOneAxisDoesNotTellTheTurn) {
  Pairs p;
  p.Q = so3::Exp(Eigen::Vector3d(1.0, 0.0, 0.0) * 5.0 * kDeg);
  p.bias = Eigen::Vector3d::Zero();
  p.one_axis = true;
  p.noise_rad = 0.01;
  RigRotationSearch search = Feed(p, 150);
  EXPECT_FALSE(search.result().has_value());  // its sigma never falls below the decision's
  const std::optional<RigRotationSearch::Result>& result = search.Decide();
  ASSERT_TRUE(result.has_value());
  EXPECT_GT(result->sigma_rad, 1.0 * kDeg);
}

}  // namespace
}  // namespace vio
