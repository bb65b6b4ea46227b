#pragma once
// Where the KLT detection's new corners recently failed to become features
// (no stereo match: the row search or the left-right LK failed). A corner
// found again at the same place within a few frames is not tried again: on a
// still or slow view the same corners fail every frame, and each try costs a
// row search (and often a stereo LK).
#include <vector>

#include <opencv2/core.hpp>

namespace vio::frontend {

class FailedCorners {
 public:
  /// Remembers a failure for `frames` frames after the one it happened in;
  /// throws std::invalid_argument for a non-positive size or frame count.
  FailedCorners(int width_px, int height_px, int frames);

  /// Starts the next frame: failures older than `frames` frames expire.
  void NextFrame() { ++frame_; }
  /// A corner at `uv_px` failed in this frame.
  void Remember(const cv::Point2f& uv_px);
  /// Whether a corner failed near `uv_px` (in its bin or one next to it) in
  /// this frame or one of the last `frames` frames.
  bool Recent(const cv::Point2f& uv_px) const;

  /// Side of the square bins failures are kept in [px]; a failure marks its
  /// bin and the 8 around it.
  static constexpr int kBinPx = 2;
  /// How long the KLT front end remembers a failure: on the still real clip
  /// V1_01_easy_micro the row searches per frame fall from 136 to 21 with 10
  /// frames (12 with 30, 36 with 4); on the rendered V2_01 20 s the ATE of
  /// KLT + MSCKF(10) was 0.0111, 0.0099, 0.0123 m with 4, 10, 30 frames
  /// (0.0109 m without the memory) [frames].
  static constexpr int kKltFrames = 10;

 private:
  /// The bin of a pixel (clamped to the image).
  int Bin(int col, int row) const;

  int cols_, rows_;
  int frames_;
  int frame_ = 0;
  /// Per bin: 1 + the frame of its last failure; 0: none.
  std::vector<int> failed_;
};

}  // namespace vio::frontend
