#pragma once
// The fast front end: FAST corners tracked by pyramidal Lucas-Kanade.
//   temporal  the left image's features are tracked from the previous left
//             image (calcOpticalFlowPyrLK) and kept only when tracking back
//             lands within klt_max_fb_px of the start (forward-backward
//             check); a track whose landmark has a position starts at its
//             projection into the IMU-predicted camera and uses two pyramid
//             levels, the others (and those that fail) start where they were
//             and use klt_pyramid_levels;
//   stereo    every feature is tracked left -> right by LK on the full-
//             resolution images with the same forward-backward check, then
//             the epipolar check on rectified rows; the initial guess is the
//             right pixel on the same rectified row at the feature's last
//             disparity; when that fails, at the disparity a 1-D ZNCC search
//             along the rectified row finds (StereoRowSearch, disparities up
//             to klt_max_disparity_px);
//   detect    features closer than klt_min_distance_px to an older one, or
//             beyond klt_per_cell in their grid cell, are dropped (youngest
//             first); when at least 5 % of klt_max_features are missing, new
//             FAST corners (at least klt_min_distance_px from every feature)
//             fill the cells in rounds (every open cell gets its first new
//             corner, strongest first, before any gets a second) up to
//             klt_per_cell per cell and klt_max_features in all; a corner
//             becomes a feature only when the row search finds it in the
//             right image and the stereo LK from there passes both checks,
//             so every new feature is a stereo observation at once;
//   reject    tracked features whose landmark reprojects too far from the
//             IMU-predicted camera are dropped (StereoFrontend::RejectOutliers).
// A feature lost in the right image stays tracked in the left one and keeps
// its id; it is an observation only in the frames where it is stereo, and is
// dropped after a few frames without a stereo match (its cell is refilled).
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "vio/frontend/feature_grid.h"
#include "vio/frontend/stereo_frontend.h"
#include "vio/frontend/stereo_row_search.h"

namespace vio::frontend {

class KltFrontend final : public StereoFrontend {
 public:
  /// Throws std::invalid_argument for a bad KLT option.
  KltFrontend(const FrontendOptions& options, const StereoRectifier& rectifier);

 protected:
  std::vector<FrameFeature> TrackFrame(const cv::Mat& left, const cv::Mat& right, const FramePrior& prior) override;

 private:
  /// A left-right match that passed the forward-backward and epipolar checks.
  struct StereoMatch {
    Eigen::Vector2d uv1_px;  ///< right image, distorted [px]
    Eigen::Vector3d z_px;    ///< rectified (u_L, u_R, v) [px]
  };
  struct Track {
    LandmarkId id;
    cv::Point2f uv0_px;              ///< left image [px]
    double disparity_px = 0;         ///< rectified u_L - u_R of the last match
    bool tracked = false;            ///< continued from the previous frame
    int age = 0;                     ///< frames tracked
    int frames_without_stereo = 0;   ///< consecutive frames not matched left-right
    std::optional<StereoMatch> match;///< this frame's
  };
  /// The stereo pair of the frame, raw and as LK pyramids.
  struct StereoImages {
    const cv::Mat& left;
    const cv::Mat& right;
    const std::vector<cv::Mat>& left_pyramid;
    const std::vector<cv::Mat>& right_pyramid;
  };

  std::vector<cv::Mat> Pyramid(const cv::Mat& image, int levels) const;
  /// Forward-backward LK from `from` to `to`; `guess` is the initial position
  /// in `to` (updated to the result). Returns per point whether it is kept.
  std::vector<bool> TrackPoints(const std::vector<cv::Mat>& from, const std::vector<cv::Mat>& to,
                                const std::vector<cv::Point2f>& points, std::vector<cv::Point2f>* guess,
                                int levels) const;
  void TrackTemporal(const std::vector<cv::Mat>& left, const FramePrior& prior);
  /// TrackPoints from the previous left image for the tracks `which`, from
  /// `guesses`; writes their results into `kept` and `moved` (per track).
  void TrackSome(const std::vector<cv::Mat>& left, const std::vector<size_t>& which,
                 std::vector<cv::Point2f> guesses, int levels, std::vector<bool>* kept,
                 std::vector<cv::Point2f>* moved) const;
  /// Where the track's landmark should appear in the left image, seen from
  /// the predicted pose; nullopt without a prediction or a position.
  std::optional<cv::Point2f> PredictedPixel(LandmarkId id, const FramePrior& prior) const;
  /// Stereo matches of the tracks: from the last disparity, then the row search.
  void MatchTracks(const StereoImages& images);
  /// The row search's disparity of a left pixel (nullopt: none found).
  std::optional<double> SearchRow(const StereoImages& images, const cv::Point2f& uv0_px) const;
  /// LK left -> right for `tracks`, each seeded at its disparity_px; sets the
  /// match of those passing the checks.
  void MatchAt(const StereoImages& images, const std::vector<Track*>& tracks);
  /// The right image's pixel of a left pixel at a rectified disparity.
  cv::Point2f RightPixelAt(const cv::Point2f& uv0_px, double disparity_px) const;
  /// Drops features without a stereo match for too long, the younger of two
  /// features closer than klt_min_distance_px and the youngest of a cell's
  /// features beyond klt_per_cell; returns the mask of where new corners may
  /// go and the count per cell.
  cv::Mat Thin(const cv::Mat& left, std::vector<int>* per_cell);
  void DetectNew(const StereoImages& images);
  /// New-feature candidates: the strongest corners, spread over the cells in
  /// rounds, that the row search finds in the right image.
  std::vector<Track> Candidates(const StereoImages& images, cv::Mat* mask, std::vector<int>* per_cell) const;
  std::vector<FrameFeature> Features();

  FeatureGrid grid_;
  StereoRowSearch row_search_;
  std::vector<cv::Mat> previous_left_;  ///< pyramid of the previous left image
  std::vector<Track> tracks_;           ///< features of the left image
};

}  // namespace vio::frontend
