#pragma once
// A 1-D stereo search along the rectified row: the disparity of a left
// feature that has none yet, to seed the left -> right Lucas-Kanade.
//
// For a left feature at rectified pixel (u, v) (integer-rounded to (u0, v0)):
//   template  T = the patch_px x patch_px patch of the rectified left image
//             centred on (u0, v0);
//   strip     S = the rectified right image's rows v0 -/+ patch_px / 2 over
//             the columns of disparities d in [0, max_disparity_px];
//   score     ZNCC(d) = sum (T - mean T)(S_d - mean S_d) / (|T - mean T| |S_d - mean S_d|)
//             (what cv::matchTemplate's TM_CCOEFF_NORMED computes);
//   accept    the best d* when ZNCC(d*) >= min_ncc and no score further
//             than 2 px from d* comes within 0.05 of it (a repeated texture
//             along the row is ambiguous);
//   refine    d = the vertex of the parabola through the scores at d* - 1,
//             d*, d* + 1; only d > 0 is returned.
// Only the patches needed are rectified: cv::remap's interpolation
// (RemapLinear, fixed_point_remap.h) on sub-rectangles of fixed-point
// rectification maps computed once. The maps cover the whole raw
// images (a rectified canvas larger than StereoRectifier's cropped one), so
// features near the raw border are searched too; only canvas pixels that
// fall inside the raw image are compared.
#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "vio/frontend/stereo_rectifier.h"

namespace vio::frontend {

class StereoRowSearch {
 public:
  /// Throws std::invalid_argument when patch_px is not an odd number >= 3,
  /// max_disparity_px < 2 or min_ncc is outside (0, 1].
  StereoRowSearch(const StereoRectifier& rectifier, int patch_px, double max_disparity_px, double min_ncc);

  /// Rectified disparity u_L - u_R [px] of the left feature at rectified
  /// pixel uv0_rect_px, searched in the raw (distorted) pair; nullopt when
  /// the patch leaves the image, is flat, or the match is weak or ambiguous.
  std::optional<double> Disparity(const cv::Mat& left, const cv::Mat& right, const Eigen::Vector2d& uv0_rect_px) const;

 private:
  static cv::Rect RectifiedBounds(const StereoRectifier& rectifier);
  void BuildMaps(const StereoRectifier& rectifier, int camera);
  /// The rectified image of `camera` over `roi` (canvas pixels).
  cv::Mat Rectified(int camera, const cv::Mat& raw, const cv::Rect& roi) const;
  /// The canvas columns valid in every row of [first_row, last_row] of `camera`.
  std::pair<int, int> ValidColumns(int camera, int first_row, int last_row) const;

  int patch_px_;
  int max_disparity_px_;
  double min_ncc_;
  cv::Rect canvas_;                  ///< the canvas in rectified pixels (both cameras)
  cv::Mat map_xy_[2];                ///< fixed-point maps (CV_16SC2) per camera
  cv::Mat map_frac_[2];              ///< interpolation tables (CV_16UC1) per camera
  std::vector<int> first_valid_[2];  ///< per canvas row, first column inside the raw image
  std::vector<int> last_valid_[2];   ///< per canvas row, last column inside the raw image
};

}  // namespace vio::frontend
