// Relative stereo poses (stereo_motion.h): noise-free frames give the motion exactly; with pixel
// noise the covariance-weighted fit's rotation is closer to the truth than the isotropic fit's
// (whose depth errors along the rays turn it), on average over draws.
#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "vio/estimator/so3.h"
#include "vio/estimator/stereo_factor.h"
#include "vio/estimator/stereo_motion.h"

namespace vio {
namespace {

RectifiedStereo Rig() {
  RectifiedStereo rig;
  rig.T_b_cl.linear() = so3::Exp(Eigen::Vector3d(0.1, -1.5, 0.05));
  rig.T_b_cl.translation() = Eigen::Vector3d(0.02, -0.06, 0.01);
  return rig;
}

// Frame a at the identity, b at T_a_b; points 2-12 m in front of the camera.
void MakeFrames(const Eigen::Isometry3d& T_a_b, double noise_px, std::mt19937* rng, StereoFrame* a, StereoFrame* b) {
  const RectifiedStereo rig = Rig();
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> n(0.0, noise_px);
  a->observations.clear();
  b->observations.clear();
  for (int i = 0; i < 80; ++i) {
    const double depth = 2.0 + 5.0 * (1.0 + u(*rng));
    const Eigen::Vector3d p_c(0.6 * depth * u(*rng), 0.4 * depth * u(*rng), depth);
    const Eigen::Vector3d p_w = rig.T_b_cl * p_c;
    Eigen::Vector3d za, zb;
    if (!StereoFactor::Project(rig, Eigen::Vector3d::Zero(), Eigen::Quaterniond::Identity(), p_w, &za)) continue;
    if (!StereoFactor::Project(rig, T_a_b.translation(), Eigen::Quaterniond(T_a_b.linear()), p_w, &zb)) continue;
    const Eigen::Vector3d na(n(*rng), n(*rng), n(*rng)), nb(n(*rng), n(*rng), n(*rng));
    a->observations.push_back({LandmarkId(i), za + na});
    b->observations.push_back({LandmarkId(i), zb + nb});
  }
}

double RotationErrorDeg(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& truth) {
  return so3::Log(Eigen::Matrix3d(estimate.linear() * truth.linear().transpose())).norm() * 180.0 / M_PI;
}

Eigen::Isometry3d Motion() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = so3::Exp(Eigen::Vector3d(0.1, 0.25, -0.15));
  T.translation() = Eigen::Vector3d(0.4, -0.1, 0.2);
  return T;
}

TEST(StereoMotion, NoiseFreeFramesGiveTheMotion) {
  std::mt19937 rng(1);
  StereoFrame a, b;
  MakeFrames(Motion(), 0.0, &rng, &a, &b);
  ModelOptions model;
  const auto plain = RelativeStereoPose(a, b, Rig(), model, 10);
  const auto weighted = WeightedRelativeStereoPose(a, b, Rig(), model, 10);
  ASSERT_TRUE(plain && weighted);
  EXPECT_LT(RotationErrorDeg(plain->T_a_b, Motion()), 1e-7);
  EXPECT_LT(RotationErrorDeg(weighted->T_a_b, Motion()), 1e-7);
  EXPECT_LT((weighted->T_a_b.translation() - Motion().translation()).norm(), 1e-9);
}

TEST(StereoMotion, TheWeightedFitsRotationIsCloserWithPixelNoise) {
  std::mt19937 rng(2);
  ModelOptions model;
  double plain_sum = 0, weighted_sum = 0;
  const int draws = 60;
  for (int k = 0; k < draws; ++k) {
    StereoFrame a, b;
    MakeFrames(Motion(), 0.5, &rng, &a, &b);
    const auto plain = RelativeStereoPose(a, b, Rig(), model, 10);
    const auto weighted = WeightedRelativeStereoPose(a, b, Rig(), model, 10);
    ASSERT_TRUE(plain && weighted);
    plain_sum += RotationErrorDeg(plain->T_a_b, Motion());
    weighted_sum += RotationErrorDeg(weighted->T_a_b, Motion());
  }
  EXPECT_LT(weighted_sum, 0.7 * plain_sum) << "mean errors [deg]: weighted " << weighted_sum / draws << ", plain "
                                           << plain_sum / draws;
}

}  // namespace
TEST(StereoMotion, TheFramesObservationOrderDoesNotMatter) {
  // The shared landmarks are matched by id: frames listing their observations in another order
  // give the same poses, bit for bit.
  std::mt19937 rng(3);
  StereoFrame a, b;
  MakeFrames(Motion(), 0.3, &rng, &a, &b);
  StereoFrame a_shuffled = a, b_reversed = b;
  std::shuffle(a_shuffled.observations.begin(), a_shuffled.observations.end(), rng);
  std::reverse(b_reversed.observations.begin(), b_reversed.observations.end());
  ModelOptions model;
  int shared = 0, shared_shuffled = 0;
  const auto plain = RelativeStereoPose(a, b, Rig(), model, 10, &shared);
  const auto shuffled = RelativeStereoPose(a_shuffled, b_reversed, Rig(), model, 10, &shared_shuffled);
  ASSERT_TRUE(plain && shuffled);
  EXPECT_EQ(shared_shuffled, shared);
  EXPECT_GT(shared, 10);
  EXPECT_EQ(shuffled->T_a_b.matrix(), plain->T_a_b.matrix());
  const auto weighted = WeightedRelativeStereoPose(a, b, Rig(), model, 10);
  const auto weighted_shuffled = WeightedRelativeStereoPose(a_shuffled, b_reversed, Rig(), model, 10);
  ASSERT_TRUE(weighted && weighted_shuffled);
  EXPECT_EQ(weighted_shuffled->T_a_b.matrix(), weighted->T_a_b.matrix());
}

}  // namespace vio
