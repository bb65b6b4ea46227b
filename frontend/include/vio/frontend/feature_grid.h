#pragma once
// A grid of square cells over the image that spreads features: at most N per
// cell, the strongest first.
#include <vector>

#include <opencv2/core.hpp>

namespace vio::frontend {

class FeatureGrid {
 public:
  /// Throws std::invalid_argument when a size is not positive.
  FeatureGrid(int width_px, int height_px, double cell_px);

  /// Cell index of a pixel (clamped to the grid), row-major.
  int Cell(const cv::Point2f& uv_px) const;
  int num_cells() const { return cols_ * rows_; }
  int cols() const { return cols_; }
  int rows() const { return rows_; }
  /// The image pixels (integer positions, inside the image) whose Cell() is `cell`.
  cv::Rect CellRect(int cell) const;

  /// Indices of the keypoints kept when each cell keeps its `per_cell`
  /// strongest (largest response), ordered by decreasing response.
  std::vector<int> Bucket(const std::vector<cv::KeyPoint>& keypoints, int per_cell) const;

 private:
  double cell_px_;
  int width_px_, height_px_;
  int cols_, rows_;
};

}  // namespace vio::frontend
