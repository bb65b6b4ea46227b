#pragma once
// The paper's front end (§5.2) on BRISK features:
//   detect    single-scale BRISK keypoints in both images: the segment-test
//             corners BRISK's detector finds at one scale, with its score
//             (segment_test_corners.h: FAST computes both 5x faster than
//             cv::BRISK), spread by a grid (the brisk_per_cell strongest per
//             cell in the left image, three times as many in the right one,
//             whose cells see other scene parts), refined to sub-pixel
//             precision on the score as BRISK does; BRISK descriptors of the
//             kept left keypoints and of the right keypoints some left one
//             may match;
//   stereo    Hamming matching left-right, mutual nearest neighbours among
//             the pairs that pass the epipolar check on rectified rows
//             (|v_L - v_R| <= max_epipolar_px, disparity in
//             (0, brisk_max_disparity_px]); only
//             stereo matches are kept;
//   temporal  the tracks seen in the last track_window_frames frames (their
//             newest left and right descriptors) are matched to the new
//             stereo features by mutual nearest neighbours, in the left and
//             right images separately; the four-way check accepts a match
//             only when the left-left AND right-right matches pick the same
//             track;
//   re-identify (reidentify_radius_px > 0) the landmarks the estimator holds
//             (FramePrior::landmarks) that no recent frame matched, by their
//             newest left and right descriptors: a stereo feature still
//             unmatched takes a landmark's id when it lies within the radius
//             of the landmark's projection into the IMU-predicted camera (in
//             u_L, u_R and v), both descriptors are within max_hamming_bits,
//             and feature and landmark are each other's nearest (summed
//             Hamming distance) among the pairs passing that gate;
//   reject    matches whose landmark reprojects too far from the IMU-predicted
//             camera are dropped (StereoFrontend::RejectOutliers);
//   new       stereo features not matched to a track start new tracks.
#include <deque>
#include <map>
#include <set>
#include <vector>

#include <opencv2/features2d.hpp>

#include "vio/frontend/feature_grid.h"
#include "vio/frontend/hamming_matching.h"
#include "vio/frontend/stereo_frontend.h"

namespace vio::frontend {

class BriskFrontend final : public StereoFrontend {
 public:
  BriskFrontend(const FrontendOptions& options, const StereoRectifier& rectifier);

 protected:
  std::vector<FrameFeature> TrackFrame(PreparedPair* pair, const FramePrior& prior) override;

 private:
  struct Detections {
    std::vector<cv::KeyPoint> keypoints;
    cv::Mat descriptors;          ///< one row per keypoint
    std::vector<bool> described;  ///< whether keypoint i's descriptor row is set
  };
  /// Stereo features with their left and right descriptors (row i = feature i).
  struct StereoFeatures {
    std::vector<FrameFeature> features;
    cv::Mat left_descriptors, right_descriptors;
  };

  /// The per_cell strongest corners of every grid cell, refined; no descriptors.
  Detections Detect(const cv::Mat& image, int per_cell) const;
  /// Descriptors of the keypoints with wanted[i]; BRISK leaves out those too
  /// near the border (described[i] false).
  void Describe(const cv::Mat& image, const std::vector<bool>& wanted, Detections* detections) const;
  /// Per described left keypoint, the right keypoints on its rectified row
  /// (within max_epipolar_px) with a disparity in (0, brisk_max_disparity_px].
  MatchCandidates StereoCandidates(const Detections& left, const Detections& right) const;
  StereoFeatures MatchStereo(const Detections& left, const Detections& right, const MatchCandidates& candidates);
  void MatchTemporal(StereoFeatures* current) const;
  /// Gives unmatched features the ids of lost landmarks (see above); returns the ids given.
  std::set<LandmarkId> Reidentify(const FramePrior& prior, StereoFeatures* current) const;
  void Remember(const StereoFeatures& current, const std::vector<LandmarkId>& rejected, const FramePrior& prior);

  /// The newest left and right descriptors of one landmark.
  struct Descriptors {
    cv::Mat left, right;
  };

  cv::Ptr<cv::BRISK> brisk_;
  FeatureGrid grid_;
  std::deque<StereoFeatures> history_;  ///< the last track_window_frames frames, newest first
  /// Re-identification: the newest descriptors of every landmark the estimator
  /// holds or a recent frame saw (empty when reidentify_radius_px is 0).
  std::map<LandmarkId, Descriptors> remembered_;
};

}  // namespace vio::frontend
