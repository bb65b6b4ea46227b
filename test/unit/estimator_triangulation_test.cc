#include "vio/estimator/triangulation.h"

#include <random>

#include <gtest/gtest.h>

#include "vio/estimator/stereo_geometry.h"

namespace vio {
namespace {

RectifiedStereo Rig() {
  RectifiedStereo stereo;
  stereo.f = 450;
  stereo.cx = 376;
  stereo.cy = 240;
  stereo.baseline = 0.11;
  stereo.T_b_cl.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;  // camera looks along body x
  return stereo;
}

Eigen::Isometry3d BodyAt(double x, double y, double yaw) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, 0);
  return T;
}

StereoView View(const Eigen::Isometry3d& T_w_b, const Eigen::Vector3d& p_w, const RectifiedStereo& stereo) {
  const Eigen::Vector3d p_cl = (T_w_b * stereo.T_b_cl).inverse() * p_w;
  return {T_w_b, ProjectRectified(p_cl, stereo)};
}

TEST(TriangulateMultiView, RecoversTheExactPointFromNoiseFreeViews) {
  const RectifiedStereo stereo = Rig();
  const Eigen::Vector3d p_w(6.0, 0.7, -0.4);
  std::vector<StereoView> views;
  for (int k = 0; k < 5; ++k) views.push_back(View(BodyAt(0.2 * k, 0.05 * k, 0.02 * k), p_w, stereo));
  const TriangulationResult result = TriangulateMultiView(views, stereo, {});
  ASSERT_TRUE(result.p_w.has_value());
  EXPECT_LT((*result.p_w - p_w).norm(), 1e-9);
}

TEST(TriangulateMultiView, NoisyViewsLandNearThePointAndBeatOneStereoPair) {
  const RectifiedStereo stereo = Rig();
  const Eigen::Vector3d p_w(8.0, -1.0, 0.5);
  std::mt19937 rng(4);
  std::normal_distribution<double> noise(0.0, 0.5);
  double multi = 0, single = 0;
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<StereoView> views;
    for (int k = 0; k < 8; ++k) {
      StereoView v = View(BodyAt(0.3 * k, 0.1 * k, -0.03 * k), p_w, stereo);
      v.z_px += Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
      views.push_back(v);
    }
    TriangulationOptions loose;  // a single 8 m stereo point is poorly constrained: accept it anyway
    loose.max_position_sigma_m = 10;
    const TriangulationResult all = TriangulateMultiView(views, stereo, {});
    const TriangulationResult one = TriangulateMultiView({views.front()}, stereo, loose);
    ASSERT_TRUE(all.p_w && one.p_w);
    multi += (*all.p_w - p_w).squaredNorm();
    single += (*one.p_w - p_w).squaredNorm();
  }
  EXPECT_LT(std::sqrt(multi / 50), 0.2);
  EXPECT_LT(multi, 0.5 * single);
}

TEST(TriangulateMultiView, RejectsInconsistentViewsAndUnconstrainedPoints) {
  const RectifiedStereo stereo = Rig();
  const Eigen::Vector3d p_w(5.0, 0.0, 0.0);
  std::vector<StereoView> views = {View(BodyAt(0, 0, 0), p_w, stereo), View(BodyAt(0.5, 0, 0), p_w, stereo)};
  views[1].z_px += Eigen::Vector3d(20, 20, -15);  // an outlier
  EXPECT_EQ(TriangulateMultiView(views, stereo, {}).failure, TriangulationFailure::kReprojection);

  const Eigen::Vector3d far_w(200.0, 0.0, 0.0);  // 0.25 px of disparity: depth unknown
  EXPECT_EQ(TriangulateMultiView({View(BodyAt(0, 0, 0), far_w, stereo)}, stereo, {}).failure,
            TriangulationFailure::kIllConditioned);

  StereoView no_disparity = View(BodyAt(0, 0, 0), p_w, stereo);
  no_disparity.z_px[1] = no_disparity.z_px[0] + 3;  // negative disparity
  EXPECT_EQ(TriangulateMultiView({no_disparity}, stereo, {}).failure, TriangulationFailure::kNoDisparity);
}

}  // namespace
}  // namespace vio
