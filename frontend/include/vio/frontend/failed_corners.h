#pragma once
// Where the KLT detection's new corners recently failed to become features
// (no stereo match: the row search or the left-right LK failed), and how. A
// corner found again at the same place within a few frames is taken to fail
// the same way without trying: on a still or slow view the same corners fail
// every frame, and each try costs a row search (and often a stereo LK).
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace vio::frontend {

/// How a corner failed to become a feature.
enum class CornerFailure : std::uint8_t {
  kNone,        ///< no failure remembered
  kRowSearch,   ///< the row search found no disparity
  kStereoMatch  ///< the row search found one, the left-right LK failed from it
};

class FailedCorners {
 public:
  /// Remembers a failure for `frames` frames after the one it happened in;
  /// throws std::invalid_argument for a non-positive size or frame count.
  FailedCorners(int width_px, int height_px, int frames);

  /// Starts the next frame: failures older than `frames` frames expire.
  void NextFrame() { ++frame_; }
  /// A corner at `uv_px` failed in this frame, as `how` says.
  void Remember(const cv::Point2f& uv_px, CornerFailure how);
  /// How the last corner near `uv_px` (in its bin or one next to it) failed
  /// in this frame or one of the last `frames` frames; kNone when none did.
  CornerFailure Recent(const cv::Point2f& uv_px) const;

  /// Side of the square bins failures are kept in [px]; a failure marks its
  /// bin and the 8 around it.
  static constexpr int kBinPx = 2;
  /// How long the KLT front end remembers a failure [frames].
  static constexpr int kKltFrames = 10;

 private:
  /// The bin of a pixel (clamped to the image).
  int Bin(int col, int row) const;

  int cols_, rows_;
  int frames_;
  int frame_ = 0;
  /// Per bin: 1 + the frame of its last failure (0: none), and how.
  std::vector<int> failed_;
  std::vector<CornerFailure> how_;
};

}  // namespace vio::frontend
