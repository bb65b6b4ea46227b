#include "vio/frontend/feature_grid.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace vio::frontend {

FeatureGrid::FeatureGrid(int width_px, int height_px, double cell_px)
    : cell_px_(cell_px), width_px_(width_px), height_px_(height_px) {
  if (width_px <= 0 || height_px <= 0 || !(cell_px > 0)) {
    throw std::invalid_argument("FeatureGrid: image size and cell size must be positive");
  }
  cols_ = static_cast<int>(std::ceil(width_px / cell_px));
  rows_ = static_cast<int>(std::ceil(height_px / cell_px));
}

int FeatureGrid::Cell(const cv::Point2f& uv_px) const {
  const int col = std::clamp(static_cast<int>(std::floor(uv_px.x / cell_px_)), 0, cols_ - 1);
  const int row = std::clamp(static_cast<int>(std::floor(uv_px.y / cell_px_)), 0, rows_ - 1);
  return row * cols_ + col;
}

// Pixel x is in column floor(x / cell_px): columns col * cell_px <= x <
// (col + 1) * cell_px, the last one reaching the image's edge (Cell clamps).
cv::Rect FeatureGrid::CellRect(int cell) const {
  const int col = cell % cols_, row = cell / cols_;
  auto first = [&](int k) { return static_cast<int>(std::ceil(k * cell_px_)); };
  const int x1 = col + 1 == cols_ ? width_px_ : std::min(first(col + 1), width_px_);
  const int y1 = row + 1 == rows_ ? height_px_ : std::min(first(row + 1), height_px_);
  return cv::Rect(cv::Point(first(col), first(row)), cv::Point(x1, y1));
}

std::vector<int> FeatureGrid::Bucket(const std::vector<cv::KeyPoint>& keypoints, int per_cell) const {
  std::vector<int> order(keypoints.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return keypoints[a].response > keypoints[b].response; });
  std::vector<int> count(static_cast<size_t>(num_cells()), 0);
  std::vector<int> kept;
  for (int i : order) {
    int& n = count[static_cast<size_t>(Cell(keypoints[i].pt))];
    if (n < per_cell) {
      ++n;
      kept.push_back(i);
    }
  }
  return kept;
}

}  // namespace vio::frontend
