#include "vio/frontend/failed_corners.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace vio::frontend {

FailedCorners::FailedCorners(int width_px, int height_px, int frames)
    : cols_((width_px + kBinPx - 1) / kBinPx), rows_((height_px + kBinPx - 1) / kBinPx), frames_(frames) {
  if (width_px <= 0 || height_px <= 0 || frames <= 0) {
    throw std::invalid_argument("FailedCorners: image size and frames must be positive");
  }
  failed_.assign(static_cast<size_t>(cols_) * static_cast<size_t>(rows_), 0);
  how_.assign(failed_.size(), CornerFailure::kNone);
}

int FailedCorners::Bin(int col, int row) const {
  return std::clamp(row, 0, rows_ - 1) * cols_ + std::clamp(col, 0, cols_ - 1);
}

void FailedCorners::Remember(const cv::Point2f& uv_px, CornerFailure how) {
  const int col = static_cast<int>(std::floor(uv_px.x / kBinPx));
  const int row = static_cast<int>(std::floor(uv_px.y / kBinPx));
  for (int r = row - 1; r <= row + 1; ++r) {
    for (int c = col - 1; c <= col + 1; ++c) {
      const auto bin = static_cast<size_t>(Bin(c, r));
      failed_[bin] = frame_ + 1;
      how_[bin] = how;
    }
  }
}

CornerFailure FailedCorners::Recent(const cv::Point2f& uv_px) const {
  const auto bin = static_cast<size_t>(Bin(static_cast<int>(std::floor(uv_px.x / kBinPx)),
                                           static_cast<int>(std::floor(uv_px.y / kBinPx))));
  const int stamp = failed_[bin];
  return stamp > 0 && frame_ - (stamp - 1) <= frames_ ? how_[bin] : CornerFailure::kNone;
}

}  // namespace vio::frontend
