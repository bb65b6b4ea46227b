// The image front ends (BRISK, KLT) on synthetic stereo pairs of a textured
// fronto-parallel plane: a pinhole pair without distortion whose right image
// is the left one shifted by the plane's disparity, so the true rectified
// measurement of every feature is known.
#include <algorithm>
#include <random>
#include <set>
#include <stdexcept>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "vio/estimator/stereo_geometry.h"
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

// Re-identification (BRISK by descriptors, KLT by patch and ZNCC): the camera
// looks at the plane (frame 0), moves kAwayPx to the side for two frames,
// longer than BRISK's one-frame track window and far enough that a third of
// frame 0 leaves the image (KLT follows the rest from the predicted pose), and
// comes back (frame 3). What the estimator holds are the landmarks of frame
// 0, triangulated at the true pose; at frame 3 they are moved by an offset
// (only then: held 22 px off in frames 1-2 with the reprojection check
// widened, KLT's LK from the predicted pixel follows some of them onto what
// lies 22 px away, and those tracks would come back consistently).
// A landmark is lost when no feature of frames 1-2 had it (KLT also keeps
// tracks that are not stereo, which are no observations), and only frame 3's
// re-identifications are counted: the plane's integer disparity puts it at
// 1.98 m rather than 2 m, so frame 1's predictions are 3 px off, and KLT gets
// back in frame 2 a few of frame 0's landmarks that frame 1 lost.
class ReidentifyTest : public ::testing::TestWithParam<std::string> {
 protected:
  static constexpr int kAwayPx = 270;

  ReidentifyTest() : rectifier_(Pinhole(0.0), Pinhole(kBaselineM)), texture_(Texture(7)) {
    options_.frontend = GetParam();
    options_.track_window_frames = 1;
    options_.reidentify_radius_px = 8.0;
  }

  FramePrior At(int shift_px) const {
    FramePrior prior;
    prior.T_w_b = Eigen::Isometry3d::Identity();
    prior.T_w_b->translation().x() = shift_px / kFocalPx * kDepthM;
    prior.landmarks = &held_;
    return prior;
  }

  struct Result {
    std::map<LandmarkId, Eigen::Vector3d> lost;      ///< frame 0's landmarks frames 1-2 lacked: z_px in frame 0
    std::map<LandmarkId, Eigen::Vector3d> returned;  ///< of those, the ones frame 3 reports: z_px in frame 3
    std::int64_t reidentified = 0;                   ///< the front end's count at frame 3
  };

  /// Frames 0, 1, 2, 3 at shifts 0, kAwayPx, kAwayPx, 0; at frame 3 the held
  /// landmarks are moved `depth_scale` times as far along their rays of frame
  /// 0, then by `offset_w_m`, and the images show `last_texture`.
  Result Run(const FrontendOptions& options, const Eigen::Vector3d& offset_w_m, const cv::Mat& last_texture,
             double depth_scale = 1.0) {
    auto frontend = MakeStereoFrontend(options, rectifier_);
    const int disparity = static_cast<int>(std::lround(kFocalPx * kBaselineM / kDepthM));
    const Pair start = View(texture_, 0, disparity);
    const StereoFrame first = frontend->Process(0, start.left, start.right, At(0));
    Hold(first, Eigen::Vector3d::Zero());
    const Pair away = View(texture_, kAwayPx, disparity);
    std::set<LandmarkId> seen;  // by a feature of frame 1 or 2, stereo or (KLT) left only
    for (int k = 1; k <= 2; ++k) {
      frontend->Process(k, away.left, away.right, At(kAwayPx));
      for (const FrameFeature& f : frontend->features()) seen.insert(f.id);
    }
    Hold(first, offset_w_m, depth_scale);
    const std::int64_t before = frontend->stats().reidentified;
    const Pair back = View(last_texture, 0, disparity);
    const StereoFrame last = frontend->Process(3, back.left, back.right, At(0));
    Result result;
    for (const StereoObservation& obs : first.observations) {
      if (seen.count(obs.landmark) == 0) result.lost[obs.landmark] = obs.z_px;
    }
    for (const StereoObservation& obs : last.observations) {
      if (result.lost.count(obs.landmark) > 0) result.returned[obs.landmark] = obs.z_px;
    }
    result.reidentified = frontend->stats().reidentified - before;
    return result;
  }

  /// The held landmarks: those of `frame` (the body at the origin), `depth_scale`
  /// times as far along their rays, moved by `offset_w_m`.
  void Hold(const StereoFrame& frame, const Eigen::Vector3d& offset_w_m, double depth_scale = 1.0) {
    held_.clear();
    const RectifiedStereo& stereo = rectifier_.rectified();
    for (const StereoObservation& obs : frame.observations) {
      const std::optional<Eigen::Vector3d> p_cl = TriangulateRectified(obs.z_px, stereo, 1.0);
      if (!p_cl) continue;
      const Eigen::Vector3d p_w = stereo.T_b_cl * (depth_scale * *p_cl) + offset_w_m;
      Landmark& landmark = held_[obs.landmark];
      landmark.id = obs.landmark;
      std::copy(p_w.data(), p_w.data() + 3, landmark.p_w);
    }
  }

  FrontendOptions options_;
  StereoRectifier rectifier_;
  cv::Mat texture_;
  std::map<LandmarkId, Landmark> held_;
};

TEST_P(ReidentifyTest, ReturningLandmarksGetTheirIdsBackAtTheirOwnPixels) {
  const Result result = Run(options_, Eigen::Vector3d::Zero(), texture_);
  ASSERT_GE(result.lost.size(), 50u);
  EXPECT_GE(result.returned.size(), result.lost.size() / 2);
  EXPECT_EQ(result.reidentified, static_cast<std::int64_t>(result.returned.size()));
  for (const auto& [id, z_px] : result.returned) {
    EXPECT_LT((z_px - result.lost.at(id)).cwiseAbs().maxCoeff(), 1.5) << "landmark " << id.value;
  }
  FrontendOptions off = options_;
  off.reidentify_radius_px = 0.0;
  const Result without = Run(off, Eigen::Vector3d::Zero(), texture_);
  EXPECT_EQ(without.lost.size(), result.lost.size());
  EXPECT_TRUE(without.returned.empty());
  EXPECT_EQ(without.reidentified, 0);
}

// No id is given outside the gate: not when every held landmark is predicted
// 22 px from where it is (the radius gate, and for KLT the ZNCC and uniqueness
// gates on what the radius holds; the reprojection check, which would also
// reject those matches, is widened out of the way), nor when the scene at the
// predicted pixels is another one (the descriptor gate; for KLT the ZNCC and
// uniqueness gates), nor when the held landmarks are twice as far along their
// rays: u_L and v are right, u_R is 12 px off (BRISK's radius gate; KLT finds
// them and matches them in stereo, and the reprojection check rejects them,
// before they are counted).
TEST_P(ReidentifyTest, AFalseRematchIsRejectedByTheGate) {
  FrontendOptions wide = options_;
  wide.max_reprojection_px = 100.0;
  const Result displaced = Run(wide, Eigen::Vector3d(0.1, 0.0, 0.0), texture_);
  ASSERT_GE(displaced.lost.size(), 50u);
  EXPECT_TRUE(displaced.returned.empty());
  EXPECT_EQ(displaced.reidentified, 0);
  const Result other_scene = Run(options_, Eigen::Vector3d::Zero(), Texture(8));
  ASSERT_GE(other_scene.lost.size(), 50u);
  EXPECT_TRUE(other_scene.returned.empty());
  EXPECT_EQ(other_scene.reidentified, 0);
  const Result deeper = Run(options_, Eigen::Vector3d::Zero(), texture_, 2.0);
  ASSERT_GE(deeper.lost.size(), 50u);
  EXPECT_TRUE(deeper.returned.empty());
  EXPECT_EQ(deeper.reidentified, 0);
  FrontendOptions bad = options_;
  bad.reidentify_radius_px = -1.0;
  EXPECT_THROW(MakeStereoFrontend(bad, rectifier_), std::invalid_argument);
}

INSTANTIATE_TEST_SUITE_P(BothFrontEnds, ReidentifyTest, ::testing::Values("brisk", "klt"),
                         [](const auto& info) { return info.param; });

// A texture that repeats every period_px rows: random grey columns, blurred.
cv::Mat RowPeriodicTexture(int period_px, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> grey(0, 255);
  cv::Mat rows(period_px, kWidth + 400, CV_8UC1);
  for (int y = 0; y < rows.rows; ++y) {
    for (int x = 0; x < rows.cols; ++x) rows.at<uchar>(y, x) = static_cast<uchar>(grey(rng));
  }
  cv::Mat texture;
  cv::repeat(rows, (kHeight + 40) / period_px + 3, 1, texture);
  cv::GaussianBlur(texture, texture, cv::Size(5, 5), 1.2);
  return texture(cv::Rect(0, period_px, kWidth + 400, kHeight + 40)).clone();
}

class KltReidentifyTest : public ReidentifyTest {};

// KLT's uniqueness gate: on a scene that repeats every 7 rows, each lost
// landmark's patch scores its best ZNCC also 7 px above and below its own
// pixel, inside the radius; no id is given back (without the gate 105 of the
// 114 lost landmarks came back, 46 of them a period off in v, which the 8 px
// reprojection check does not reject).
TEST_P(KltReidentifyTest, AnAmbiguousRematchIsRejected) {
  texture_ = RowPeriodicTexture(7, 7);
  const Result result = Run(options_, Eigen::Vector3d::Zero(), texture_);
  ASSERT_GE(result.lost.size(), 50u);
  EXPECT_TRUE(result.returned.empty());
  EXPECT_EQ(result.reidentified, 0);
}

// KLT's distance gate: frame 3 comes back with the held landmarks predicted
// far out of view, so new corners fill the returning part under new ids,
// many on the lost landmarks' own points; in frame 4, predicted right again,
// a lost landmark is not given back on top of such a track (features stay
// klt_min_distance_px apart, up to the rounding of the mask's pixels), and
// some are given back where no track took their place.
TEST_P(KltReidentifyTest, ALandmarkIsNotGivenBackWhereATrackIs) {
  auto frontend = MakeStereoFrontend(options_, rectifier_);
  const int disparity = static_cast<int>(std::lround(kFocalPx * kBaselineM / kDepthM));
  const Pair start = View(texture_, 0, disparity), away = View(texture_, kAwayPx, disparity);
  const StereoFrame first = frontend->Process(0, start.left, start.right, At(0));
  Hold(first, Eigen::Vector3d::Zero());
  for (int k = 1; k <= 2; ++k) frontend->Process(k, away.left, away.right, At(kAwayPx));
  Hold(first, Eigen::Vector3d(50.0, 0.0, 0.0));
  frontend->Process(3, start.left, start.right, At(0));
  Hold(first, Eigen::Vector3d::Zero());
  const std::int64_t before = frontend->stats().reidentified;
  frontend->Process(4, start.left, start.right, At(0));
  EXPECT_GT(frontend->stats().reidentified, before);
  const std::vector<FrameFeature>& features = frontend->features();
  double closest = 1e9;
  for (size_t i = 0; i < features.size(); ++i) {
    for (size_t j = i + 1; j < features.size(); ++j) {
      closest = std::min(closest, (features[i].uv0_px - features[j].uv0_px).norm());
    }
  }
  EXPECT_GT(closest, options_.klt_min_distance_px - 1.5);
}

INSTANTIATE_TEST_SUITE_P(Klt, KltReidentifyTest, ::testing::Values("klt"),
                         [](const auto& info) { return info.param; });

TEST(MakeStereoFrontend, RejectsTheFeaturesFrontEnd) {
  FrontendOptions options;
  options.frontend = "features";
  const StereoRectifier rectifier(Pinhole(0.0), Pinhole(kBaselineM));
  EXPECT_THROW(MakeStereoFrontend(options, rectifier), std::invalid_argument);
}

}  // namespace
}  // namespace vio::frontend
