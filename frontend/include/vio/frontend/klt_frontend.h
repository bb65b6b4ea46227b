#pragma once
// The fast front end: FAST corners tracked by pyramidal Lucas-Kanade.
//   temporal  the left image's features are tracked from the previous left
//             image (calcOpticalFlowPyrLK) and kept only when tracking back
//             lands within klt_max_fb_px of the start (forward-backward
//             check, skipped when the forward LK ends within 0.3 px of the
//             IMU-predicted pixel; both pyramids are built once per frame,
//             in Prepare, and the left one serves the next frame); a track whose
//             landmark has a position starts at its
//             projection into the IMU-predicted camera and uses two pyramid
//             levels, the others (and those that fail) start where they were
//             and use klt_pyramid_levels;
//   stereo    every feature is tracked left -> right by LK on the full-
//             resolution images with the same forward-backward check, then
//             the epipolar check on rectified rows; the initial guess is the
//             right pixel on the same rectified row at the feature's last
//             disparity (no backward LK when the forward one ends within
//             0.3 px of it); when that fails, at the disparity a 1-D ZNCC
//             search along the rectified row finds (StereoRowSearch, disparities up
//             to klt_max_disparity_px);
//   detect    features closer than klt_min_distance_px to an older one, or
//             beyond klt_per_cell in their grid cell, are dropped (youngest
//             first); when at least 5 % of klt_max_features are missing, new
//             FAST corners (at least klt_min_distance_px from every feature)
//             fill the cells in rounds (every open cell gets its first new
//             corner, strongest first, before any gets a second) up to
//             klt_per_cell per cell and klt_max_features in all (FAST runs
//             only on the cells below klt_per_cell, or its corners of the
//             whole image come prepared: the same corners); a corner
//             becomes a feature only when the row search finds it in the
//             right image and the stereo LK from there passes both checks,
//             so every new feature is a stereo observation at once; a
//             corner found where one failed in the last
//             FailedCorners::kKltFrames frames is taken to fail the same way
//             without a row search or LK (FailedCorners);
//   re-identify (reidentify_radius_px > 0; after detect's thinning, before
//             its new corners) the landmarks the estimator holds
//             (FramePrior::landmarks) that are no current track, by the 21 px
//             left-image patch remembered around each one's last tracked
//             pixel: the patch is sought by ZNCC within the radius of the
//             landmark's projection into the IMU-predicted camera (raw left
//             pixels, whole-pixel positions, parabola-refined); the best
//             position is taken when it scores at least 0.9 (and
//             klt_min_ncc), no position further than 2 px from it scores
//             within 0.05 of it, and it lies where a new corner may go (at
//             least klt_min_distance_px from every feature, in a cell below
//             klt_per_cell); it is then matched in stereo like a new corner
//             (row search, then LK with both checks), and only a stereo match
//             becomes a track again, with the landmark's id, checked against
//             the predicted pose like every temporal match (reject); a
//             track's patch is cut from the last left image it was tracked in
//             when it is lost (so a track lost in this frame's temporal step
//             can be found again at once), and kept while the estimator holds
//             its landmark and it is no track;
//   reject    tracked features whose landmark reprojects too far from the
//             IMU-predicted camera are dropped (StereoFrontend::RejectOutliers).
// A feature lost in the right image stays tracked in the left one and keeps
// its id; it is an observation only in the frames where it is stereo, and is
// dropped after a few frames without a stereo match (its cell is refilled).
#include <map>
#include <optional>
#include <set>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "vio/frontend/failed_corners.h"
#include "vio/frontend/feature_grid.h"
#include "vio/frontend/stereo_frontend.h"
#include "vio/frontend/stereo_row_search.h"

namespace vio::frontend {

class KltFrontend final : public StereoFrontend {
 public:
  /// Throws std::invalid_argument for a bad KLT option.
  KltFrontend(const FrontendOptions& options, const StereoRectifier& rectifier);

 protected:
  std::vector<FrameFeature> TrackFrame(PreparedPair* pair, const FramePrior& prior) override;
  /// The pyramids, and with `with_corners` the left image's FAST corners.
  void PrepareImages(bool with_corners, PreparedPair* pair) const override;

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

  /// Forward-backward LK from `from` to `to`; `guess` is the initial position
  /// in `to` (updated to the result). Returns per point whether it is kept:
  /// the forward LK converged inside the image and either ended within
  /// `agree_px` of its guess or tracking back lands within klt_max_fb_px of
  /// the start (the backward LK runs only for those points).
  std::vector<bool> TrackPoints(const std::vector<cv::Mat>& from, const std::vector<cv::Mat>& to,
                                const std::vector<cv::Point2f>& points, std::vector<cv::Point2f>* guess,
                                int levels, double agree_px) const;
  void TrackTemporal(const std::vector<cv::Mat>& left, const FramePrior& prior);
  /// TrackPoints from the previous left image for the tracks `which`, from
  /// `guesses`; writes their results into `kept` and `moved` (per track).
  void TrackSome(const std::vector<cv::Mat>& left, const std::vector<size_t>& which,
                 std::vector<cv::Point2f> guesses, int levels, double agree_px, std::vector<bool>* kept,
                 std::vector<cv::Point2f>* moved) const;
  /// Where the track's landmark should appear in the left image, seen from
  /// the predicted pose; nullopt without a prediction or a position.
  std::optional<cv::Point2f> PredictedPixel(LandmarkId id, const FramePrior& prior) const;
  /// The raw left pixel of a world point seen from the body pose T_w_b;
  /// nullopt behind the camera or outside the camera model.
  std::optional<cv::Point2f> LeftPixel(const Eigen::Vector3d& p_w, const Eigen::Isometry3d& T_w_b) const;
  /// Whether p lies inside the image (borders included).
  static bool Inside(const cv::Point2f& p, const cv::Mat& image);
  /// The ids of the current tracks.
  std::set<LandmarkId> TrackIds() const;
  /// Stereo matches of the tracks: from the last disparity, then the row search.
  void MatchTracks(const StereoImages& images);
  /// The row search's disparity of a left pixel (nullopt: none found).
  std::optional<double> SearchRow(const StereoImages& images, const cv::Point2f& uv0_px);
  /// LK left -> right for `tracks`, each seeded at its disparity_px; sets the
  /// match of those passing the checks (TrackPoints' agree_px).
  void MatchAt(const StereoImages& images, const std::vector<Track*>& tracks, double agree_px);
  /// The right image's pixel of a left pixel at a rectified disparity.
  cv::Point2f RightPixelAt(const cv::Point2f& uv0_px, double disparity_px) const;
  /// Drops features without a stereo match for too long, the younger of two
  /// features closer than klt_min_distance_px and the youngest of a cell's
  /// features beyond klt_per_cell; sets mask_ (where new corners may go) and
  /// per_cell_ (the count per cell).
  void Thin(const cv::Mat& left);
  /// New features from FAST corners where mask_ (from Thin) allows them.
  void DetectNew(const StereoImages& images, const PreparedPair& pair);
  /// Lost landmarks found again (see above) become tracks where `mask`
  /// allows them; returns their ids.
  std::set<LandmarkId> Reidentify(const StereoImages& images, const FramePrior& prior, cv::Mat* mask,
                                  std::vector<int>* per_cell);
  /// The best ZNCC position of `patch` within reidentify_radius_px of
  /// `predicted` in the left image when it passes the score and uniqueness
  /// gates; nullopt otherwise.
  std::optional<cv::Point2f> FindPatch(const cv::Mat& left, const cv::Mat& patch, const cv::Point2f& predicted) const;
  /// Drops the tracks of the ids RejectOutliers rejected.
  void DropTracks(const std::vector<LandmarkId>& rejected);
  /// The tracks of the previous frame that are no tracks now leave their
  /// patch in the previous left image (remembered_) and previous_tracks_.
  void RememberLost();
  /// With re-identification on, at the end of a frame: RememberLost (the
  /// tracks rejected since), only the lost landmarks the estimator holds stay
  /// remembered, and the tracks are noted for the next frame.
  void Remember(const FramePrior& prior);
  /// New-feature candidates: the strongest corners, spread over the cells in
  /// rounds, that the row search finds in the right image.
  std::vector<Track> Candidates(const StereoImages& images, const PreparedPair& pair);
  /// The FAST corners of the cells below klt_per_cell (per_cell_), sorted
  /// strongest first; held in corners_.
  const std::vector<cv::KeyPoint>& OpenCellCorners(const PreparedPair& pair);
  std::vector<FrameFeature> Features();

  FeatureGrid grid_;
  StereoRowSearch row_search_;
  /// New corners that found no stereo match in the last frames: not tried again.
  FailedCorners failed_corners_;
  std::vector<cv::Mat> previous_left_;  ///< pyramid of the previous left image
  std::vector<Track> tracks_;           ///< features of the left image
  /// Per-frame buffers, kept to reuse their memory: where new corners may go
  /// (Thin), features per grid cell, the corners of the open cells and of
  /// one cell.
  cv::Mat mask_;
  std::vector<int> per_cell_;
  std::vector<cv::KeyPoint> corners_, cell_corners_;
  /// Where a track was in the previous left image.
  struct Seen {
    LandmarkId id;
    cv::Point2f uv0_px;  ///< left image [px]
    int age = 0;         ///< frames tracked
  };
  /// The last appearance of a lost landmark in the left image.
  struct Appearance {
    cv::Mat patch;  ///< CV_8UC1 square around the last tracked pixel
    int age = 0;    ///< frames the track had been tracked
  };
  /// Re-identification (both empty when reidentify_radius_px is 0): the
  /// tracks of the previous frame, and the appearance of every landmark the
  /// estimator holds that is no track.
  std::vector<Seen> previous_tracks_;
  std::map<LandmarkId, Appearance> remembered_;
};

}  // namespace vio::frontend
