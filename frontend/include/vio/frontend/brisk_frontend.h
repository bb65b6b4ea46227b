#pragma once
// The paper's front end (§5.2) on BRISK features:
//   detect    BRISK keypoints in both images, spread by a grid (the
//             brisk_per_cell strongest per cell in the left image, three
//             times as many in the right one, whose cells see other scene
//             parts), and their descriptors;
//   stereo    brute-force Hamming matching left-right with a cross check,
//             then the epipolar check on rectified rows (|v_L - v_R| <=
//             max_epipolar_px, positive disparity); only stereo matches are
//             kept;
//   temporal  the tracks seen in the last track_window_frames frames (their
//             newest left and right descriptors) are matched brute-force to
//             the new stereo features, in the left and right images
//             separately; the four-way check accepts a match only when the
//             left-left AND right-right matches pick the same track;
//   reject    matches whose landmark reprojects too far from the IMU-predicted
//             camera are dropped (StereoFrontend::RejectOutliers);
//   new       stereo features not matched to a track start new tracks.
#include <deque>
#include <vector>

#include <opencv2/features2d.hpp>

#include "vio/frontend/feature_grid.h"
#include "vio/frontend/stereo_frontend.h"

namespace vio::frontend {

class BriskFrontend final : public StereoFrontend {
 public:
  BriskFrontend(const FrontendOptions& options, const StereoRectifier& rectifier);

 protected:
  std::vector<FrameFeature> TrackFrame(const cv::Mat& left, const cv::Mat& right, const FramePrior& prior) override;

 private:
  struct Detections {
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;  ///< one row per keypoint
  };
  /// Stereo features with their left and right descriptors (row i = feature i).
  struct StereoFeatures {
    std::vector<FrameFeature> features;
    cv::Mat left_descriptors, right_descriptors;
  };

  Detections Detect(const cv::Mat& image, int per_cell) const;
  StereoFeatures MatchStereo(const Detections& left, const Detections& right);
  void MatchTemporal(StereoFeatures* current) const;
  void Remember(const StereoFeatures& current, const std::vector<LandmarkId>& rejected);

  cv::Ptr<cv::BRISK> brisk_;
  cv::BFMatcher matcher_;
  FeatureGrid grid_;
  std::deque<StereoFeatures> history_;  ///< the last track_window_frames frames, newest first
};

}  // namespace vio::frontend
