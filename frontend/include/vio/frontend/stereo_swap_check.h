#pragma once
// Exchanged stereo images (cam0's files are the right camera's), seen from the images themselves
// (docs/bad-input.md): the features path checks its pixel pairs (stereo_frames.h); an image front
// end, given exchanged images, finds no stereo match at a positive disparity and would only lose
// tracking. On the first pairs with texture, corners of each image are searched along the rectified
// row of the other (StereoRowSearch): with the images as given, cam0's corners match in cam1 at a
// positive disparity; exchanged, cam1's corners match in cam0 instead.
#include <string>

#include <opencv2/core.hpp>

#include "vio/frontend/stereo_rectifier.h"
#include "vio/frontend/stereo_row_search.h"

namespace vio::frontend {

class StereoSwapCheck {
 public:
  static constexpr int kCornersPerImage = 100;
  static constexpr double kMinDisparityPx = 2.0;  ///< nearer to 0 (far points) both directions match
  static constexpr int kDecisionMatches = 200;    ///< decides once this many matches were found either way
  static constexpr int kMaxFrames = 30;           ///< or after this many pairs (then: not exchanged)
  static constexpr int kMinExchangedMatches = 100;
  static constexpr int kExchangedRatio = 3;  ///< exchanged when this many times the matches as given

  explicit StereoSwapCheck(const StereoRectifier& rectifier);

  /// One raw (distorted) pair, cam0's image and cam1's, grey; nothing once decided.
  void Add(const cv::Mat& cam0, const cv::Mat& cam1);
  bool decided() const { return decided_; }
  /// Set once decided and the images match only exchanged.
  const std::string& problem() const { return problem_; }
  int matches_as_given() const { return as_given_; }
  int matches_exchanged() const { return exchanged_; }

 private:
  /// Corners of `first` matched in `second` at a disparity above kMinDisparityPx.
  int Matches(const cv::Mat& first, const cv::Mat& second) const;
  void Decide();

  StereoRectifier rectifier_;
  StereoRowSearch row_search_;
  int as_given_ = 0;
  int exchanged_ = 0;
  int frames_ = 0;
  bool decided_ = false;
  std::string problem_;
};

}  // namespace vio::frontend
