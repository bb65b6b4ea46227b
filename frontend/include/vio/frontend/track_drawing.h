#pragma once
// Debug images of a front end: the left and right images side by side, each
// stereo feature as a dot in both (green when it continues a track, yellow
// when new), left-only features in red, and each track's recent path in the
// left image (blue).
#include <deque>
#include <unordered_map>
#include <vector>

#include <opencv2/core.hpp>

#include "vio/frontend/stereo_frontend.h"

namespace vio::frontend {

class TrackDrawer {
 public:
  /// `tail_frames` recent positions of each track are drawn as its path.
  explicit TrackDrawer(int tail_frames = 10) : tail_frames_(tail_frames) {}

  /// The BGR image (2 width x height) of one frame's features; call once per
  /// frame in order (it remembers the tracks' paths).
  cv::Mat Draw(const cv::Mat& left, const cv::Mat& right, const std::vector<FrameFeature>& features);

 private:
  int tail_frames_;
  std::unordered_map<std::int64_t, std::deque<cv::Point2f>> tails_;
};

}  // namespace vio::frontend
