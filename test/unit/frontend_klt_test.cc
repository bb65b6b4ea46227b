// The stereo row search (StereoRowSearch) and the KLT front end at large
// disparities and large image motion, on raw (distorted, real EuRoC
// calibration) stereo pairs made from a textured plane parallel to the
// rectified image plane: its rectified disparity is one known number
// everywhere, and each raw pixel shows the texture at its rectified position,
// so the true measurement of every pixel is known.
#include <algorithm>
#include <map>
#include <random>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "euroc_calibration.h"
#include "vio/frontend/failed_corners.h"
#include "vio/frontend/stereo_frontend.h"
#include "vio/frontend/stereo_row_search.h"

namespace vio::frontend {
namespace {

using test::EurocCamera;

/// The texture extends this far beyond the rectified image [px].
constexpr int kMarginPx = 200;
constexpr int kPatchPx = 11;
constexpr double kMaxDisparityPx = 128;
constexpr double kMinNcc = 0.8;

// Random grey rectangles at several sizes: corners everywhere.
cv::Mat RandomTexture(cv::Size size, unsigned seed) {
  std::mt19937 rng(seed);
  cv::Mat texture(size, CV_8UC1, cv::Scalar(128));
  for (int side : {50, 20, 8}) {
    std::uniform_int_distribution<int> x(0, size.width - 1), y(0, size.height - 1), grey(0, 255), s(side / 2, side);
    const int count = static_cast<int>(texture.total()) / (side * side * 2);
    for (int i = 0; i < count; ++i) {
      cv::rectangle(texture, cv::Rect(x(rng), y(rng), s(rng), s(rng)), cv::Scalar(grey(rng)), cv::FILLED);
    }
  }
  cv::GaussianBlur(texture, texture, cv::Size(3, 3), 0.8);
  return texture;
}

// The raw image of `camera` seeing `texture` as its rectified image, shifted
// left by `disparity_px` for the right camera; texture pixel (kMarginPx,
// kMarginPx) is rectified pixel (0, 0) of the left camera.
cv::Mat RawView(const StereoRectifier& rectifier, int camera, const cv::Mat& texture, double disparity_px,
               double shift_px = 0.0) {
  const CameraModel& model = rectifier.camera_model(camera);
  cv::Mat map_x(model.height(), model.width(), CV_32FC1), map_y(model.height(), model.width(), CV_32FC1);
  for (int y = 0; y < model.height(); ++y) {
    for (int x = 0; x < model.width(); ++x) {
      const std::optional<Eigen::Vector2d> rect = rectifier.Rectify(camera, Eigen::Vector2d(x, y));
      const Eigen::Vector2d uv = rect.value_or(Eigen::Vector2d(-1e4, -1e4));
      map_x.at<float>(y, x) = static_cast<float>(uv.x() + kMarginPx + shift_px + (camera == 1 ? disparity_px : 0.0));
      map_y.at<float>(y, x) = static_cast<float>(uv.y() + kMarginPx);
    }
  }
  cv::Mat raw;
  cv::remap(texture, raw, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(128));
  return raw;
}

struct RawPair {
  cv::Mat left, right;
};

// The pair seen after the rectified left camera moved right by shift_px /
// disparity_px baselines (the plane's texture moves shift_px to the left).
RawPair MakePair(const StereoRectifier& rectifier, const cv::Mat& texture, double disparity_px,
                 double shift_px = 0.0) {
  return {RawView(rectifier, 0, texture, 0.0, shift_px), RawView(rectifier, 1, texture, disparity_px, shift_px)};
}

class DistortedPlaneTest : public ::testing::Test {
 protected:
  DistortedPlaneTest()
      : rectifier_(EurocCamera(0), EurocCamera(1)),
        texture_(RandomTexture(cv::Size(752 + 2 * kMarginPx + 300, 480 + 2 * kMarginPx), 11)) {}

  /// Five frames moving right: the same frames with whole-image corners
  /// prepared (as the read-ahead thread does) as with FAST on open cells only.
  void ExpectSameFramesWithPreparedCorners(const FrontendOptions& options);

  StereoRectifier rectifier_;
  cv::Mat texture_;
};

TEST_F(DistortedPlaneTest, FindsTheTrueDisparityOverTheWholeImage) {
  const StereoRowSearch search(rectifier_, kPatchPx, kMaxDisparityPx, kMinNcc);
  for (const double disparity : {7.3, 42.0, 101.6}) {
    const RawPair pair = MakePair(rectifier_, texture_, disparity);
    int searched = 0, found = 0, accurate = 0, near_border = 0;
    for (int y = 4; y < 480; y += 12) {
      for (int x = 4; x < 752; x += 12) {
        const std::optional<Eigen::Vector2d> rect = rectifier_.Rectify(0, Eigen::Vector2d(x, y));
        ASSERT_TRUE(rect.has_value());
        // Only where the right camera sees the point.
        if (!rectifier_.Rectify(1, Eigen::Vector2d(x, y)) ||
            rect->x() - disparity < 40 || rect->x() > 700 || y < 20 || y > 460) {
          continue;
        }
        ++searched;
        const std::optional<double> d = search.Disparity(pair.left, pair.right, *rect);
        if (!d) continue;
        ++found;
        // A seed for the stereo LK: within a pixel.
        accurate += std::abs(*d - disparity) < 1.0;
        // Raw pixels outside StereoRectifier's cropped rectified image.
        near_border += rect->x() < 0 || rect->y() < 0 || rect->y() > 479;
      }
    }
    ASSERT_GT(searched, 500) << disparity;
    EXPECT_GE(found, 0.8 * searched) << disparity;
    EXPECT_GE(accurate, 0.98 * found) << disparity;
    EXPECT_GT(near_border, 0) << disparity;
  }
}

TEST_F(DistortedPlaneTest, RejectsFlatAndRepeatedTexture) {
  const StereoRowSearch search(rectifier_, kPatchPx, kMaxDisparityPx, kMinNcc);
  const cv::Mat flat(texture_.size(), CV_8UC1, cv::Scalar(90));
  cv::Mat stripes(texture_.size(), CV_8UC1);
  for (int x = 0; x < stripes.cols; ++x) stripes.col(x).setTo((x / 5) % 2 ? 200 : 40);
  cv::GaussianBlur(stripes, stripes, cv::Size(3, 3), 0.8);
  const RawPair flat_pair = MakePair(rectifier_, flat, 30.0), striped_pair = MakePair(rectifier_, stripes, 30.0);
  for (int y = 150; y < 330; y += 30) {
    for (int x = 250; x < 600; x += 30) {
      const Eigen::Vector2d rect = *rectifier_.Rectify(0, Eigen::Vector2d(x, y));
      EXPECT_FALSE(search.Disparity(flat_pair.left, flat_pair.right, rect).has_value()) << x << " " << y;
      EXPECT_FALSE(search.Disparity(striped_pair.left, striped_pair.right, rect).has_value()) << x << " " << y;
    }
  }
}

TEST_F(DistortedPlaneTest, RejectsBadParameters) {
  EXPECT_THROW(StereoRowSearch(rectifier_, 10, kMaxDisparityPx, kMinNcc), std::invalid_argument);
  EXPECT_THROW(StereoRowSearch(rectifier_, 1, kMaxDisparityPx, kMinNcc), std::invalid_argument);
  EXPECT_THROW(StereoRowSearch(rectifier_, kPatchPx, 1.0, kMinNcc), std::invalid_argument);
  EXPECT_THROW(StereoRowSearch(rectifier_, kPatchPx, kMaxDisparityPx, 0.0), std::invalid_argument);
  EXPECT_THROW(StereoRowSearch(rectifier_, kPatchPx, kMaxDisparityPx, 1.5), std::invalid_argument);
}

// The KLT front end on a real-calibration pair at a near plane (disparity
// 101.6 px, about 0.47 m away): every stereo feature at the true disparity.
// The LK runs on the raw images, where the two views of a patch 100 px apart
// differ by the change of the distortion's local scale (a few percent), so
// the disparity is within about 1 % rather than 0.1 px.
TEST_F(DistortedPlaneTest, KltMatchesANearPlaneInStereo) {
  FrontendOptions options;
  options.frontend = "klt";
  auto frontend = MakeStereoFrontend(options, rectifier_);
  const double disparity = 101.6;
  const RawPair pair = MakePair(rectifier_, texture_, disparity);
  const StereoFrame frame = frontend->Process(0, pair.left, pair.right, FramePrior{});
  ASSERT_GE(frame.observations.size(), 150u);
  std::vector<double> errors;
  for (const StereoObservation& obs : frame.observations) {
    errors.push_back(std::abs(obs.z_px.x() - obs.z_px.y() - disparity));
  }
  std::sort(errors.begin(), errors.end());
  EXPECT_LT(errors[errors.size() / 2], 0.25);
  EXPECT_LT(errors[errors.size() * 98 / 100], 1.2);
  EXPECT_LT(frontend->stats().MedianRowDifferencePx(), 0.2);
}

// Temporal tracking over a 150 px jump, too far for the pyramid from the
// previous pixel: found from the projection of each track's landmark into the
// predicted camera.
TEST_F(DistortedPlaneTest, KltTracksAJumpFromThePredictedPose) {
  const double disparity = 40.0, shift = 150.0;
  const RectifiedStereo& stereo = rectifier_.rectified();
  Eigen::Isometry3d T_cl0_cl1 = Eigen::Isometry3d::Identity();
  T_cl0_cl1.translation().x() = shift / disparity * stereo.baseline;
  FramePrior before, after;
  before.T_w_b = Eigen::Isometry3d::Identity();
  after.T_w_b = stereo.T_b_cl * T_cl0_cl1 * stereo.T_b_cl.inverse();
  const RawPair first = MakePair(rectifier_, texture_, disparity);
  const RawPair second = MakePair(rectifier_, texture_, disparity, shift);
  FrontendOptions options;
  options.frontend = "klt";
  // Share of the first frame's features continued at the true shift.
  auto continued = [&](const FramePrior& prior) {
    auto frontend = MakeStereoFrontend(options, rectifier_);
    const StereoFrame frame0 = frontend->Process(0, first.left, first.right, before);
    const StereoFrame frame1 = frontend->Process(1, second.left, second.right, prior);
    std::map<std::int64_t, double> u0;
    for (const StereoObservation& obs : frame0.observations) u0[obs.landmark.value] = obs.z_px.x();
    int count = 0;
    for (const StereoObservation& obs : frame1.observations) {
      const auto it = u0.find(obs.landmark.value);
      count += it != u0.end() && std::abs(it->second - obs.z_px.x() - shift) < 1.0;
    }
    return static_cast<double>(count) / static_cast<double>(frame0.observations.size());
  };
  const double predicted = continued(after), unpredicted = continued(FramePrior{});
  // A fifth of the first frame leaves the image.
  EXPECT_GT(predicted, 0.6);
  EXPECT_LT(unpredicted, 0.2);
}

// A temporal track starts its LK at the IMU-predicted pixel; when that
// prediction is a few pixels off (here 3 px, a poor IMU prediction), the LK
// must still end every continued track at its true pixel. (With 8 px off the
// random-rectangle texture gives about a fifth of the continued tracks a
// wrong pixel that the forward-backward check accepts, with or without the
// agreement gate that skips the backward LK near a seed.)
TEST_F(DistortedPlaneTest, KltContinuesTracksAtTheTruePixelWhenThePredictionIsOff) {
  const double disparity = 40.0, shift = 30.0;
  const RectifiedStereo& stereo = rectifier_.rectified();
  const RawPair first = MakePair(rectifier_, texture_, disparity);
  const RawPair second = MakePair(rectifier_, texture_, disparity, shift);
  FrontendOptions options;
  options.frontend = "klt";
  for (const double predicted_shift : {shift, shift + 3.0, shift - 3.0}) {
    SCOPED_TRACE(predicted_shift);
    Eigen::Isometry3d T_cl0_cl1 = Eigen::Isometry3d::Identity();
    T_cl0_cl1.translation().x() = predicted_shift / disparity * stereo.baseline;
    FramePrior before, after;
    before.T_w_b = Eigen::Isometry3d::Identity();
    after.T_w_b = stereo.T_b_cl * T_cl0_cl1 * stereo.T_b_cl.inverse();
    auto frontend = MakeStereoFrontend(options, rectifier_);
    const StereoFrame frame0 = frontend->Process(0, first.left, first.right, before);
    const StereoFrame frame1 = frontend->Process(1, second.left, second.right, after);
    std::map<std::int64_t, double> u0;
    for (const StereoObservation& obs : frame0.observations) u0[obs.landmark.value] = obs.z_px.x();
    int continued = 0, wrong = 0;
    for (const StereoObservation& obs : frame1.observations) {
      const auto it = u0.find(obs.landmark.value);
      if (it == u0.end()) continue;
      ++continued;
      wrong += std::abs(it->second - obs.z_px.x() - shift) > 1.0;
    }
    EXPECT_GT(continued, static_cast<int>(frame0.observations.size()) / 2);
    EXPECT_EQ(wrong, 0);
  }
}

// A front end whose pairs were prepared with the whole image's FAST corners
// (as the read-ahead thread does) emits the same frames as one that runs
// FAST only in the grid cells that need features, over frames that lose
// tracks at the border and refill them.
// Default options (most cells open: FAST on the whole image), and one
// feature per cell with a large budget (after the first frame few cells are
// open: FAST on each grid row's span of open cells).
TEST_F(DistortedPlaneTest, WholeImageCornersGiveTheSameFramesAsPerCellDetection) {
  FrontendOptions options;
  options.frontend = "klt";
  ExpectSameFramesWithPreparedCorners(options);
  options.klt_per_cell = 1;
  options.klt_max_features = 1000;
  ExpectSameFramesWithPreparedCorners(options);
}

void DistortedPlaneTest::ExpectSameFramesWithPreparedCorners(const FrontendOptions& options) {
  const auto per_cell = MakeStereoFrontend(options, rectifier_);
  const auto whole = MakeStereoFrontend(options, rectifier_);
  PreparedPair prepared;
  for (int k = 0; k < 5; ++k) {
    const RawPair pair = MakePair(rectifier_, texture_, 30.0, 12.0 * k);
    const StereoFrame expected = per_cell->Process(k, pair.left, pair.right, FramePrior{});
    whole->Prepare(pair.left, pair.right, /*with_corners=*/true, &prepared);
    ASSERT_TRUE(prepared.corners_ready);
    const StereoFrame got = whole->Process(k, &prepared, FramePrior{});
    ASSERT_EQ(got.observations.size(), expected.observations.size()) << "frame " << k;
    ASSERT_GT(got.observations.size(), 80u);
    for (size_t i = 0; i < got.observations.size(); ++i) {
      EXPECT_EQ(got.observations[i].landmark, expected.observations[i].landmark);
      EXPECT_EQ(got.observations[i].z_px, expected.observations[i].z_px);
    }
  }
  EXPECT_GT(per_cell->stats().new_tracks, per_cell->stats().observations_per_frame.front());
}

// The same pair again and again, its right image flat on the right half:
// the left corners seen there find no stereo match. The detection tries
// them in the first frame, takes them to fail in the next
// FailedCorners::kKltFrames frames (no row search: only the few corners
// the first frame's features left untried), then tries them again.
TEST_F(DistortedPlaneTest, KltDoesNotRetryCornersThatFailedRecently) {
  FrontendOptions options;
  options.frontend = "klt";
  options.klt_max_features = 1000;  // the open cells keep wanting features
  auto frontend = MakeStereoFrontend(options, rectifier_);
  RawPair pair = MakePair(rectifier_, texture_, 30.0);
  pair.right.colRange(pair.right.cols / 2, pair.right.cols).setTo(cv::Scalar(128));
  std::vector<std::int64_t> searches;
  std::vector<size_t> observations;
  for (int k = 0; k < FailedCorners::kKltFrames + 2; ++k) {
    const std::int64_t before = frontend->stats().row_searches;
    observations.push_back(frontend->Process(k, pair.left, pair.right, FramePrior{}).observations.size());
    searches.push_back(frontend->stats().row_searches - before);
  }
  EXPECT_GT(searches[0], 500);
  for (size_t k = 1; k <= FailedCorners::kKltFrames; ++k) EXPECT_LE(searches[k], 10) << "frame " << k;
  EXPECT_GT(searches[FailedCorners::kKltFrames + 1], searches[0] / 2);
  for (size_t k = 1; k < observations.size(); ++k) EXPECT_NEAR(observations[k], observations[0], 5) << "frame " << k;
}

TEST_F(DistortedPlaneTest, KltRejectsABadFeatureBudget) {
  FrontendOptions options;
  options.frontend = "klt";
  options.klt_max_features = 0;
  EXPECT_THROW(MakeStereoFrontend(options, rectifier_), std::invalid_argument);
  options.klt_max_features = 300;
  options.klt_min_ncc = 2.0;
  EXPECT_THROW(MakeStereoFrontend(options, rectifier_), std::invalid_argument);
}

}  // namespace
}  // namespace vio::frontend
