#pragma once
// The fast front end: FAST corners tracked by pyramidal Lucas-Kanade.
//   temporal  the left image's features are tracked from the previous left
//             image (calcOpticalFlowPyrLK) and kept only when tracking back
//             lands within klt_max_fb_px of the start (forward-backward check);
//   detect    features closer than klt_min_distance_px to an older one, or
//             beyond klt_per_cell in their grid cell, are dropped (youngest
//             first); new FAST corners (at least klt_min_distance_px from
//             every feature) fill the cells holding fewer than klt_per_cell
//             features, strongest first;
//   stereo    every left feature is tracked left -> right with the same
//             forward-backward check, then the epipolar check on rectified
//             rows; the initial guess is the right pixel on the same
//             rectified row at the feature's previous disparity (new
//             features: the median disparity of the frame's features);
//   reject    tracked features whose landmark reprojects too far from the
//             IMU-predicted camera are dropped (StereoFrontend::RejectOutliers).
// A feature lost in the right image stays tracked in the left one and keeps
// its id; it is an observation only in the frames where it is stereo, and is
// dropped after a few frames without a stereo match (its cell is refilled).
#include <vector>

#include <opencv2/core.hpp>

#include "vio/frontend/feature_grid.h"
#include "vio/frontend/stereo_frontend.h"

namespace vio::frontend {

class KltFrontend final : public StereoFrontend {
 public:
  KltFrontend(const FrontendOptions& options, const StereoRectifier& rectifier);

 protected:
  std::vector<FrameFeature> TrackFrame(const cv::Mat& left, const cv::Mat& right, const FramePrior& prior) override;

 private:
  struct Track {
    LandmarkId id;
    cv::Point2f uv0_px;           ///< left image [px]
    double disparity_px = 0;      ///< rectified u_L - u_R when last matched
    bool has_disparity = false;
    bool tracked = false;         ///< continued from the previous frame
    int age = 0;                  ///< frames tracked
    int frames_without_stereo = 0;///< consecutive frames not matched left-right
  };

  std::vector<cv::Mat> Pyramid(const cv::Mat& image) const;
  /// Forward-backward LK from `from` to `to`; `guess` is the initial position
  /// in `to` (updated to the result). Returns per point whether it is kept.
  std::vector<bool> TrackPoints(const std::vector<cv::Mat>& from, const std::vector<cv::Mat>& to,
                                const std::vector<cv::Point2f>& points, std::vector<cv::Point2f>* guess) const;
  void TrackTemporal(const std::vector<cv::Mat>& left);
  /// Drops features without a stereo match for too long, the younger of two
  /// features closer than klt_min_distance_px and the youngest of a cell's
  /// features beyond klt_per_cell; returns the mask
  /// of where new corners may go and the count per cell.
  cv::Mat Thin(const cv::Mat& left, std::vector<int>* per_cell);
  void DetectNew(const cv::Mat& left);
  /// The right image's pixel of a left pixel at a rectified disparity.
  cv::Point2f RightPixelAt(const cv::Point2f& uv0_px, double disparity_px) const;
  std::vector<FrameFeature> MatchStereo(const std::vector<cv::Mat>& left, const std::vector<cv::Mat>& right);

  FeatureGrid grid_;
  std::vector<cv::Mat> previous_left_;  ///< pyramid of the previous left image
  std::vector<Track> tracks_;           ///< features of the left image
};

}  // namespace vio::frontend
