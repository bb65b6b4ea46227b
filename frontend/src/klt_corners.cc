// KLT detection's corners (klt_frontend.h, detect): FAST's corners of the
// whole image in the grid cells that need features, found on those cells
// only when few are open.
#include <algorithm>

#include <opencv2/features2d.hpp>

#include "vio/frontend/klt_frontend.h"

namespace vio::frontend {
namespace {

/// FAST reads 3 px around a pixel, and its nonmax suppression compares the
/// 8 neighbours' scores: a cell grown by this much gives its corners exactly
/// as FAST on the whole image does [px].
constexpr int kFastMarginPx = 4;

}  // namespace

// The FAST corners of the cells below klt_per_cell, strongest first (ties
// in row-major order, as a stable sort of FAST's output gives). With most
// cells open, FAST runs on the whole image; else on each grid row's span from
// its first to its last open cell, grown by kFastMarginPx, which holds the
// pixels FAST reads for a corner of the span and for its nonmax suppression's
// neighbours. Either way the corners kept are those of the whole image in
// the open cells.
const std::vector<cv::KeyPoint>& KltFrontend::OpenCellCorners(const PreparedPair& pair) {
  corners_.clear();
  auto open = [&](int cell) { return per_cell_[static_cast<size_t>(cell)] < options().klt_per_cell; };
  auto keep_open = [&](const std::vector<cv::KeyPoint>& corners, const cv::Point2f& offset, int grid_row) {
    for (cv::KeyPoint k : corners) {
      k.pt += offset;
      const int cell = grid_.Cell(k.pt);
      if (open(cell) && (grid_row < 0 || cell / grid_.cols() == grid_row)) corners_.push_back(k);
    }
  };
  int open_cells = 0;
  for (int c = 0; c < grid_.num_cells(); ++c) open_cells += open(c);
  if (pair.corners_ready) {
    keep_open(pair.corners, cv::Point2f(0, 0), -1);
  } else if (2 * open_cells >= grid_.num_cells()) {
    cv::FAST(pair.left, cell_corners_, options().klt_fast_threshold, /*nonmaxSuppression=*/true);
    keep_open(cell_corners_, cv::Point2f(0, 0), -1);
  } else {
    const cv::Rect image(0, 0, pair.left.cols, pair.left.rows);
    for (int row = 0; row < grid_.rows(); ++row) {
      int first = -1, last = -1;
      for (int col = 0; col < grid_.cols(); ++col) {
        if (!open(row * grid_.cols() + col)) continue;
        if (first < 0) first = col;
        last = col;
      }
      if (first < 0) continue;
      const cv::Rect span = grid_.CellRect(row * grid_.cols() + first) | grid_.CellRect(row * grid_.cols() + last);
      const cv::Rect grown = (span + cv::Size(2 * kFastMarginPx, 2 * kFastMarginPx) -
                              cv::Point(kFastMarginPx, kFastMarginPx)) & image;
      cv::FAST(pair.left(grown), cell_corners_, options().klt_fast_threshold, /*nonmaxSuppression=*/true);
      keep_open(cell_corners_, cv::Point2f(static_cast<float>(grown.x), static_cast<float>(grown.y)), row);
    }
  }
  std::sort(corners_.begin(), corners_.end(), [](const cv::KeyPoint& a, const cv::KeyPoint& b) {
    if (a.response != b.response) return a.response > b.response;
    return a.pt.y != b.pt.y ? a.pt.y < b.pt.y : a.pt.x < b.pt.x;
  });
  return corners_;
}

}  // namespace vio::frontend
