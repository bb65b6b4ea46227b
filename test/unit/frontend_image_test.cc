// The image front ends (BRISK, KLT) on synthetic stereo pairs of a textured
// fronto-parallel plane: a pinhole pair without distortion whose right image
// is the left one shifted by the plane's disparity, so the true rectified
// measurement of every feature is known.
#include <random>
#include <set>
#include <stdexcept>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "vio/frontend/stereo_frontend.h"
#include "vio/frontend/track_drawing.h"

namespace vio::frontend {
namespace {

constexpr double kBaselineM = 0.11;
constexpr double kDepthM = 2.0;
constexpr double kFocalPx = 450.0;
constexpr int kWidth = 752, kHeight = 480;

CameraCalibration Pinhole(double x_m) {
  CameraCalibration cam;
  cam.intrinsics = Eigen::Vector4d(kFocalPx, kFocalPx, 376.0, 240.0);
  cam.T_b_c = Eigen::Isometry3d::Identity();
  cam.T_b_c.translation() = Eigen::Vector3d(x_m, 0, 0);
  return cam;
}

// A wide texture of random grey rectangles at several sizes: many corners.
cv::Mat Texture(unsigned seed) {
  std::mt19937 rng(seed);
  cv::Mat texture(kHeight + 40, kWidth + 400, CV_8UC1, cv::Scalar(128));
  for (int size : {60, 25, 10}) {
    std::uniform_int_distribution<int> x(0, texture.cols - 1), y(0, texture.rows - 1), grey(0, 255), s(size / 2, size);
    const int count = static_cast<int>(texture.total()) / (size * size * 2);
    for (int i = 0; i < count; ++i) {
      cv::rectangle(texture, cv::Rect(x(rng), y(rng), s(rng), s(rng)), cv::Scalar(grey(rng)), cv::FILLED);
    }
  }
  cv::GaussianBlur(texture, texture, cv::Size(3, 3), 0.8);
  return texture;
}

// The stereo pair of the plane seen from the camera shifted right by shift_px
// (the scene moves left in the image).
struct Pair {
  cv::Mat left, right;
};
Pair View(const cv::Mat& texture, int shift_px, int disparity_px) {
  return {texture(cv::Rect(100 + shift_px, 20, kWidth, kHeight)).clone(),
          texture(cv::Rect(100 + shift_px + disparity_px, 20, kWidth, kHeight)).clone()};
}

class ImageFrontendTest : public ::testing::TestWithParam<std::string> {
 protected:
  ImageFrontendTest() : rectifier_(Pinhole(0.0), Pinhole(kBaselineM)), texture_(Texture(7)) {
    options_.frontend = GetParam();
  }
  /// The rectified disparity of the plane [px] and the image shift giving it.
  int DisparityPx() const { return static_cast<int>(std::lround(kFocalPx * kBaselineM / kDepthM)); }
  double RectifiedDisparityPx() const {
    return rectifier_.rectified().f / kFocalPx * DisparityPx();
  }

  FrontendOptions options_;
  StereoRectifier rectifier_;
  cv::Mat texture_;
};

TEST_P(ImageFrontendTest, StereoMatchesHaveTheTrueDisparityAndRow) {
  auto frontend = MakeStereoFrontend(options_, rectifier_);
  const Pair pair = View(texture_, 0, DisparityPx());
  const StereoFrame frame = frontend->Process(1000, pair.left, pair.right, FramePrior{});
  EXPECT_EQ(frame.t_ns, 1000);
  ASSERT_GE(frame.observations.size(), 100u);
  int good = 0;
  for (const StereoObservation& obs : frame.observations) {
    good += std::abs(obs.z_px.x() - obs.z_px.y() - RectifiedDisparityPx()) < 1.0;
  }
  EXPECT_GE(good, 0.95 * frame.observations.size());
  EXPECT_LT(frontend->stats().MedianRowDifferencePx(), 0.2);
  EXPECT_GT(frontend->stats().stereo_inliers, 0);
}

TEST_P(ImageFrontendTest, TracksKeepTheirIdsOverTime) {
  auto frontend = MakeStereoFrontend(options_, rectifier_);
  std::vector<StereoFrame> frames;
  for (int k = 0; k < 4; ++k) {
    const Pair pair = View(texture_, 4 * k, DisparityPx());
    frames.push_back(frontend->Process(k, pair.left, pair.right, FramePrior{}));
  }
  std::map<std::int64_t, Eigen::Vector3d> first;
  for (const StereoObservation& obs : frames[0].observations) first[obs.landmark.value] = obs.z_px;
  const double expected_shift = -12.0 * rectifier_.rectified().f / kFocalPx;
  int continued = 0, consistent = 0;
  std::set<std::int64_t> ids;
  for (const StereoObservation& obs : frames[3].observations) {
    EXPECT_TRUE(ids.insert(obs.landmark.value).second) << "id " << obs.landmark.value << " twice in a frame";
    const auto it = first.find(obs.landmark.value);
    if (it == first.end()) continue;
    ++continued;
    consistent += std::abs(obs.z_px.x() - it->second.x() - expected_shift) < 1.5;
  }
  EXPECT_GE(continued, 0.6 * frames[0].observations.size());
  EXPECT_GE(consistent, 0.95 * continued);
  // The two-way index agrees with the emitted frames.
  const FeatureTracks& tracks = frontend->tracks();
  for (const StereoObservation& obs : frames[3].observations) {
    EXPECT_EQ(tracks.FramesOf(obs.landmark).back(), 3);
  }
  EXPECT_EQ(tracks.TracksIn(3).size(), frames[3].observations.size());
}

TEST_P(ImageFrontendTest, RejectsMatchesThatContradictThePredictedPose) {
  auto frontend = MakeStereoFrontend(options_, rectifier_);
  FramePrior at_origin;
  at_origin.T_w_b = Eigen::Isometry3d::Identity();
  const Pair first = View(texture_, 0, DisparityPx());
  frontend->Process(0, first.left, first.right, at_origin);
  // The camera moved right by 4 px at depth kDepthM = 4 / f * kDepthM metres.
  FramePrior truth, wrong;
  truth.T_w_b = Eigen::Isometry3d::Identity();
  truth.T_w_b->translation().x() = 4.0 / kFocalPx * kDepthM;
  wrong.T_w_b = Eigen::Isometry3d::Identity();
  wrong.T_w_b->translation().x() = -0.2;  // 45 px the other way
  auto second = MakeStereoFrontend(options_, rectifier_);
  second->Process(0, first.left, first.right, at_origin);
  const Pair moved = View(texture_, 4, DisparityPx());
  frontend->Process(1, moved.left, moved.right, truth);
  second->Process(1, moved.left, moved.right, wrong);
  const FrontendStats& good = frontend->stats();
  const FrontendStats& bad = second->stats();
  ASSERT_GT(good.temporal_matches, 50);
  EXPECT_LT(good.rejected_reprojection, 0.05 * good.temporal_matches);
  // Every checkable match is rejected (KLT features never stereo have no position).
  EXPECT_GE(bad.rejected_reprojection, 0.9 * bad.temporal_matches);
}

TEST_P(ImageFrontendTest, RejectsBadImagesAndOptions) {
  auto frontend = MakeStereoFrontend(options_, rectifier_);
  const cv::Mat small(100, 100, CV_8UC1, cv::Scalar(0));
  EXPECT_THROW(frontend->Process(0, small, small, FramePrior{}), std::invalid_argument);
  FrontendOptions bad = options_;
  bad.grid_cell_px = 0;
  EXPECT_THROW(MakeStereoFrontend(bad, rectifier_), std::invalid_argument);
  bad = options_;
  bad.max_hamming_bits = 600;
  EXPECT_THROW(MakeStereoFrontend(bad, rectifier_), std::invalid_argument);
}

TEST_P(ImageFrontendTest, DrawsBothImagesSideBySide) {
  auto frontend = MakeStereoFrontend(options_, rectifier_);
  const Pair pair = View(texture_, 0, DisparityPx());
  frontend->Process(0, pair.left, pair.right, FramePrior{});
  TrackDrawer drawer;
  const cv::Mat image = drawer.Draw(pair.left, pair.right, frontend->features());
  EXPECT_EQ(image.cols, 2 * kWidth);
  EXPECT_EQ(image.rows, kHeight);
  EXPECT_EQ(image.type(), CV_8UC3);
}

INSTANTIATE_TEST_SUITE_P(BothFrontEnds, ImageFrontendTest, ::testing::Values("brisk", "klt"),
                         [](const auto& info) { return info.param; });

// BRISK matches in stereo only up to brisk_max_disparity_px: the plane's
// disparity (about 25 px) is found under the default and under a cap just
// above it; under a cap below it every match is gone but the few false ones
// the cap allows.
TEST(BriskFrontend, StereoMatchesStopAtTheLargestDisparity) {
  const StereoRectifier rectifier(Pinhole(0.0), Pinhole(kBaselineM));
  const int disparity = static_cast<int>(std::lround(kFocalPx * kBaselineM / kDepthM));
  const Pair pair = View(Texture(7), 0, disparity);
  auto stereo = [&](double cap_px) {
    FrontendOptions options;
    options.frontend = "brisk";
    options.brisk_max_disparity_px = cap_px;
    const std::vector<StereoObservation> observations =
        MakeStereoFrontend(options, rectifier)->Process(1, pair.left, pair.right, FramePrior{}).observations;
    for (const StereoObservation& obs : observations) EXPECT_LE(obs.z_px.x() - obs.z_px.y(), cap_px);
    return observations.size();
  };
  const size_t all = stereo(FrontendOptions().brisk_max_disparity_px);
  ASSERT_GE(all, 100u);
  EXPECT_EQ(stereo(disparity + 3.0), all);
  EXPECT_LE(stereo(disparity - 3.0), all / 50);
  FrontendOptions bad;
  bad.frontend = "brisk";
  bad.brisk_max_disparity_px = 0.0;
  EXPECT_THROW(MakeStereoFrontend(bad, rectifier), std::invalid_argument);
}

TEST(MakeStereoFrontend, RejectsTheFeaturesFrontEnd) {
  FrontendOptions options;
  options.frontend = "features";
  const StereoRectifier rectifier(Pinhole(0.0), Pinhole(kBaselineM));
  EXPECT_THROW(MakeStereoFrontend(options, rectifier), std::invalid_argument);
}

}  // namespace
}  // namespace vio::frontend
