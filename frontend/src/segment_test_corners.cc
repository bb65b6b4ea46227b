#include "vio/frontend/segment_test_corners.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <opencv2/features2d.hpp>

namespace vio::frontend {
namespace {

constexpr int kCircle = 16;  ///< pixels on the circle
constexpr int kArc = 9;      ///< contiguous pixels the test needs
/// The 3x3 neighbourhood's circles reach this far from the corner [px].
constexpr int kRefineMarginPx = 4;
/// The refined maximum stays within the 3x3 neighbourhood it is fitted on [px].
constexpr double kMaxRefinementPx = 1.0;

/// The circle of radius 3 around the centre, clockwise from the top.
constexpr std::array<std::array<int, 2>, kCircle> kCircleOffsets = {{{0, -3},
                                                                     {1, -3},
                                                                     {2, -2},
                                                                     {3, -1},
                                                                     {3, 0},
                                                                     {3, 1},
                                                                     {2, 2},
                                                                     {1, 3},
                                                                     {0, 3},
                                                                     {-1, 3},
                                                                     {-2, 2},
                                                                     {-3, 1},
                                                                     {-3, 0},
                                                                     {-3, -1},
                                                                     {-2, -2},
                                                                     {-1, -3}}};

}  // namespace

int SegmentTestScore(const cv::Mat& image, int x, int y) {
  const int centre = image.at<std::uint8_t>(y, x);
  // Circle pixel - centre, the first kArc - 1 repeated at the end so every arc
  // is contiguous in the array.
  std::array<int, kCircle + kArc - 1> difference{};
  for (int k = 0; k < kCircle; ++k) {
    difference[k] = image.at<std::uint8_t>(y + kCircleOffsets[k][1], x + kCircleOffsets[k][0]) - centre;
  }
  for (int k = kCircle; k < kCircle + kArc - 1; ++k) difference[k] = difference[k - kCircle];
  // Per arc, the weakest pixel bounds the threshold: t < min(d) for a
  // brighter arc, t < min(-d) = -max(d) for a darker one.
  int best = 0;
  for (int start = 0; start < kCircle; ++start) {
    int lowest = difference[start], highest = difference[start];
    for (int k = 1; k < kArc; ++k) {
      lowest = std::min(lowest, difference[start + k]);
      highest = std::max(highest, difference[start + k]);
    }
    best = std::max({best, lowest, -highest});
  }
  return std::max(best - 1, 0);
}

SegmentTestScoreMap::SegmentTestScoreMap(const cv::Mat& image)
    : image_(image), scores_(image.size(), CV_32S, cv::Scalar(-1)) {}

int SegmentTestScoreMap::operator()(int x, int y) {
  int& score = scores_.at<int>(y, x);
  if (score < 0) score = SegmentTestScore(image_, x, y);
  return score;
}

void RefineCorner(SegmentTestScoreMap* scores, cv::KeyPoint* corner) {
  const int x = static_cast<int>(corner->pt.x), y = static_cast<int>(corner->pt.y);
  const cv::Mat& image = scores->image();
  if (x < kRefineMarginPx || y < kRefineMarginPx || x >= image.cols - kRefineMarginPx ||
      y >= image.rows - kRefineMarginPx) {
    return;  // the neighbours' circles would leave the image
  }
  // Least-squares fit of s = a + b dx + c dy + e dx dy + d (dx^2 - 2/3) +
  // f (dy^2 - 2/3) to the 9 scores: on the 3x3 grid these regressors are
  // orthogonal, so each coefficient is one normalized sum.
  double a = 0.0, b = 0.0, c = 0.0, d = 0.0, e = 0.0, f = 0.0;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      const double s = (*scores)(x + dx, y + dy);
      a += s / 9.0;
      b += dx * s / 6.0;
      c += dy * s / 6.0;
      e += dx * dy * s / 4.0;
      d += (dx * dx - 2.0 / 3.0) * s / 2.0;
      f += (dy * dy - 2.0 / 3.0) * s / 2.0;
    }
  }
  // The quadratic's maximum: H o = -g with H = [2d e; e 2f], g = (b, c).
  const double det = 4.0 * d * f - e * e;
  if (!(d < 0.0 && det > 0.0)) return;  // no maximum: the pixel and its score stay
  const double ox = std::clamp(-(2.0 * f * b - e * c) / det, -kMaxRefinementPx, kMaxRefinementPx);
  const double oy = std::clamp(-(2.0 * d * c - e * b) / det, -kMaxRefinementPx, kMaxRefinementPx);
  corner->pt = cv::Point2f(static_cast<float>(x + ox), static_cast<float>(y + oy));
  corner->response =
      static_cast<float>(a + b * ox + c * oy + e * ox * oy + d * (ox * ox - 2.0 / 3.0) + f * (oy * oy - 2.0 / 3.0));
}

std::vector<cv::KeyPoint> DetectSegmentTestCorners(int threshold, SegmentTestScoreMap* scores) {
  std::vector<cv::KeyPoint> raw;
  cv::FAST(scores->image(), raw, threshold, /*nonmaxSuppression=*/false, cv::FastFeatureDetector::TYPE_9_16);
  // Without suppression cv::FAST leaves the scores out: the raw corners are
  // scored first, so that during the suppression the known scores are
  // exactly the corners' (a pixel that is no corner counts as 0).
  for (cv::KeyPoint& c : raw) {
    c.response = static_cast<float>((*scores)(static_cast<int>(c.pt.x), static_cast<int>(c.pt.y)));
  }
  auto corner_score = [&](int x, int y) { return scores->Known(x, y) ? (*scores)(x, y) : 0; };
  auto is_local_maximum = [&](int x, int y) {
    const int s = corner_score(x, y);
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if (corner_score(x + dx, y + dy) > s) return false;
      }
    }
    return true;
  };
  std::vector<cv::KeyPoint> corners;
  for (cv::KeyPoint& c : raw) {
    if (!is_local_maximum(static_cast<int>(c.pt.x), static_cast<int>(c.pt.y))) continue;
    c.size = kBriskKeypointSizePx;
    c.angle = -1.0f;
    corners.push_back(c);
  }
  return corners;
}

}  // namespace vio::frontend
