#pragma once
// Corners of the segment test on the 16-pixel circle of radius 3 with 9
// contiguous pixels (FAST 9-16, the test BRISK's single-scale AGAST detector
// runs) and its score: the largest threshold t at which the pixel is still a
// corner, i.e. 9 contiguous circle pixels all brighter than I(p) + t or all
// darker than I(p) - t. This is the score BRISK ranks and refines its
// single-scale keypoints by; cv::FAST finds the same corners and the same
// score, several times faster than cv::BRISK's detector at one scale.
#include <vector>

#include <opencv2/core.hpp>

namespace vio::frontend {

/// BRISK's keypoint size at the finest scale [px]; its descriptor picks the
/// sampling pattern's scale from it.
inline constexpr float kBriskKeypointSizePx = 12.0f;

/// Score of pixel (x, y) of an 8-bit grey image: the largest t >= 0 with 9
/// contiguous circle pixels all > I + t or all < I - t, 0 when there is none.
/// Requires 3 <= x < cols - 3 and 3 <= y < rows - 3.
int SegmentTestScore(const cv::Mat& image, int x, int y);

/// SegmentTestScore of one image's pixels, each computed at most once (the
/// detector scores every raw corner, the refinement their neighbours).
class SegmentTestScoreMap {
 public:
  /// Keeps a reference: `image` must outlive the map.
  explicit SegmentTestScoreMap(const cv::Mat& image);
  /// The score of pixel (x, y), same requirements as SegmentTestScore.
  int operator()(int x, int y);
  /// Whether (x, y)'s score has been computed.
  bool Known(int x, int y) const { return scores_.at<int>(y, x) >= 0; }
  const cv::Mat& image() const { return image_; }

 private:
  const cv::Mat& image_;
  cv::Mat scores_;  ///< CV_32S, -1 where not computed yet
};

/// Refines a corner found at an integer pixel as BRISK refines its
/// single-scale keypoints: the quadratic fitted (least squares) to the scores
/// of its 3x3 neighbourhood gives the position (its maximum, at most one pixel
/// away) and the response (the value there). A corner whose fitted quadratic
/// has no maximum stays as it is, and so does a corner within 4 px of the
/// border (its neighbours' circles would leave the image).
void RefineCorner(SegmentTestScoreMap* scores, cv::KeyPoint* corner);

/// FAST 9-16 corners at `threshold` that no 8-neighbour corner outscores
/// (equal neighbours are both kept, as BRISK's suppression keeps plateaus;
/// cv::FAST's own suppression drops both, which halves how many corners
/// survive from frame to frame), each a cv::KeyPoint at its integer pixel with
/// the segment-test score as response and size kBriskKeypointSizePx. Scores
/// every raw corner into `scores`, which must hold no other scores yet.
std::vector<cv::KeyPoint> DetectSegmentTestCorners(int threshold, SegmentTestScoreMap* scores);

}  // namespace vio::frontend
