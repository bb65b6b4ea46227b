#include "vio/frontend/stereo_row_search.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include <glog/logging.h>
#include <opencv2/core/hal/intrin.hpp>
#include <opencv2/imgproc.hpp>

#include "correlation_peak.h"
#include "vio/frontend/fixed_point_remap.h"

namespace vio::frontend {
namespace {

using detail::kMinPatchStdGrey;
using detail::kPeakHalfWidthPx;
using detail::kUniquenessMargin;
using detail::ParabolaVertex;

/// Samples per image side when bounding the rectified images [count].
constexpr int kBorderSamples = 64;

// Per window position x, sum over the template of T(r, c) S(r, x + c), in
// integers (the same result in any order): per template row, two template
// columns at a time against eight positions, each pair of products summed by
// one 16-bit multiply-add (grey levels fit in 16 bits, their products and
// sums in 32).
std::vector<int> CrossSums(const cv::Mat& strip, const cv::Mat& templ, int positions) {
  const int n = templ.rows;
  // Eight positions per step, and the second column of the last odd pair
  // (weight 0) read one past: the buffers are padded for both.
  const int padded = (positions + 7) / 8 * 8;
  std::vector<int> cross(static_cast<size_t>(padded), 0);
  std::vector<std::int16_t> row16(static_cast<size_t>(padded + n + 1), 0);
  for (int r = 0; r < n; ++r) {
    const uchar* row = strip.ptr<uchar>(r);
    for (int x = 0; x < strip.cols; ++x) row16[static_cast<size_t>(x)] = row[x];
    const uchar* t = templ.ptr<uchar>(r);
    for (int c = 0; c < n; c += 2) {
      const int second = c + 1 < n ? t[c + 1] : 0;
      const cv::v_int16x8 weights = cv::v_reinterpret_as_s16(cv::v_setall_s32(t[c] | (second << 16)));
      const std::int16_t* from = row16.data() + c;
      for (int x = 0; x < padded; x += 8) {
        cv::v_int16x8 pairs_low, pairs_high;
        cv::v_zip(cv::v_load(from + x), cv::v_load(from + x + 1), pairs_low, pairs_high);
        int* sums = cross.data() + x;
        cv::v_store(sums, cv::v_dotprod(pairs_low, weights, cv::v_load(sums)));
        cv::v_store(sums + 4, cv::v_dotprod(pairs_high, weights, cv::v_load(sums + 4)));
      }
    }
  }
  cross.resize(static_cast<size_t>(positions));
  return cross;
}

// ZNCC of the square template against each window of the strip (both
// CV_8UC1 with the template's rows), one score per window position, from
// integer sums: ZNCC = (sum TS - sum T sum S / N) / sqrt(var T var S), with
// var X = sum X^2 - (sum X)^2 / N. Written out because cv::matchTemplate goes
// through DFTs whose set-up dominates at this size (measured per whole
// search, patch rectification included: 29 us with it, 12 us with this).
std::vector<float> ZnccAlongStrip(const cv::Mat& strip, const cv::Mat& templ) {
  const int n = templ.rows;
  const double count = static_cast<double>(n) * n;
  double t_sum = 0, t_sum2 = 0;
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      const double v = templ.at<uchar>(r, c);
      t_sum += v;
      t_sum2 += v * v;
    }
  }
  const double t_var = t_sum2 - t_sum * t_sum / count;
  std::vector<int> column_sum(static_cast<size_t>(strip.cols), 0), column_sum2(column_sum);
  for (int r = 0; r < n; ++r) {
    const uchar* row = strip.ptr<uchar>(r);
    for (int x = 0; x < strip.cols; ++x) {
      column_sum[static_cast<size_t>(x)] += row[x];
      column_sum2[static_cast<size_t>(x)] += row[x] * row[x];
    }
  }
  const int positions = strip.cols - n + 1;
  const std::vector<int> cross_sums = CrossSums(strip, templ, positions);
  std::vector<float> scores(static_cast<size_t>(positions), 0.0f);
  for (int x = 0; x < positions; ++x) {
    int sum = 0, sum2 = 0;
    for (int c = 0; c < n; ++c) {
      sum += column_sum[static_cast<size_t>(x + c)];
      sum2 += column_sum2[static_cast<size_t>(x + c)];
    }
    const int cross = cross_sums[static_cast<size_t>(x)];
    const double s_var = sum2 - static_cast<double>(sum) * sum / count;
    if (s_var > 1e-6) {
      scores[static_cast<size_t>(x)] = static_cast<float>((cross - t_sum * sum / count) / std::sqrt(t_var * s_var));
    }
  }
  return scores;
}

}  // namespace

StereoRowSearch::StereoRowSearch(const StereoRectifier& rectifier, int patch_px, double max_disparity_px,
                                 double min_ncc)
    : patch_px_(patch_px), max_disparity_px_(static_cast<int>(std::ceil(max_disparity_px))), min_ncc_(min_ncc) {
  if (patch_px < 3 || patch_px % 2 == 0) throw std::invalid_argument("StereoRowSearch: patch_px must be odd, >= 3");
  if (!(max_disparity_px >= 2)) throw std::invalid_argument("StereoRowSearch: max_disparity_px must be >= 2");
  if (!(min_ncc > 0 && min_ncc <= 1)) throw std::invalid_argument("StereoRowSearch: min_ncc must be in (0, 1]");
  canvas_ = RectifiedBounds(rectifier);
  for (int k = 0; k < 2; ++k) BuildMaps(rectifier, k);
}

// The bounding box of both raw images' borders in rectified pixels.
cv::Rect StereoRowSearch::RectifiedBounds(const StereoRectifier& rectifier) {
  double u_min = 1e9, u_max = -1e9, v_min = 1e9, v_max = -1e9;
  for (int k = 0; k < 2; ++k) {
    const CameraModel& camera = rectifier.camera_model(k);
    const double w = camera.width() - 1, h = camera.height() - 1;
    for (double t = 0; t <= 1.0; t += 1.0 / kBorderSamples) {
      for (const Eigen::Vector2d& uv : {Eigen::Vector2d(t * w, 0), Eigen::Vector2d(t * w, h), Eigen::Vector2d(0, t * h),
                                        Eigen::Vector2d(w, t * h)}) {
        const std::optional<Eigen::Vector2d> rect = rectifier.Rectify(k, uv);
        if (!rect) continue;
        u_min = std::min(u_min, rect->x()), u_max = std::max(u_max, rect->x());
        v_min = std::min(v_min, rect->y()), v_max = std::max(v_max, rect->y());
      }
    }
  }
  CHECK_LT(u_min, u_max) << "no raw border pixel can be rectified";
  const cv::Point corner(static_cast<int>(std::floor(u_min)), static_cast<int>(std::floor(v_min)));
  return cv::Rect(corner, cv::Point(static_cast<int>(std::ceil(u_max)) + 1, static_cast<int>(std::ceil(v_max)) + 1));
}

// Canvas pixel (x, y) is rectified pixel canvas_.tl() + (x, y); its ray in
// rectified camera k, rotated into camera k, projects to the raw pixel read.
void StereoRowSearch::BuildMaps(const StereoRectifier& rectifier, int camera) {
  const RectifiedStereo& r = rectifier.rectified();
  const Eigen::Matrix3d R_cam_rect = rectifier.R_rect_cam(camera).transpose();
  cv::Mat map_x(canvas_.size(), CV_32FC1, cv::Scalar(-1)), map_y(canvas_.size(), CV_32FC1, cv::Scalar(-1));
  std::vector<int>& first = first_valid_[camera];
  std::vector<int>& last = last_valid_[camera];
  first.assign(static_cast<size_t>(canvas_.height), canvas_.width);
  last.assign(static_cast<size_t>(canvas_.height), -1);
  for (int y = 0; y < canvas_.height; ++y) {
    for (int x = 0; x < canvas_.width; ++x) {
      const Eigen::Vector3d ray((canvas_.x + x - r.cx) / r.f, (canvas_.y + y - r.cy) / r.f, 1.0);
      const std::optional<Eigen::Vector2d> uv = rectifier.camera_model(camera).Project(R_cam_rect * ray);
      if (!uv) continue;
      map_x.at<float>(y, x) = static_cast<float>(uv->x());
      map_y.at<float>(y, x) = static_cast<float>(uv->y());
      first[static_cast<size_t>(y)] = std::min(first[static_cast<size_t>(y)], x);
      last[static_cast<size_t>(y)] = std::max(last[static_cast<size_t>(y)], x);
    }
  }
  cv::convertMaps(map_x, map_y, map_xy_[camera], map_frac_[camera], CV_16SC2);
}

cv::Mat StereoRowSearch::Rectified(int camera, const cv::Mat& raw, const cv::Rect& roi) const {
  cv::Mat patch;
  RemapLinear(raw, map_xy_[camera](roi), map_frac_[camera](roi), &patch);
  return patch;
}

std::pair<int, int> StereoRowSearch::ValidColumns(int camera, int first_row, int last_row) const {
  int first = 0, last = canvas_.width - 1;
  for (int y = first_row; y <= last_row; ++y) {
    first = std::max(first, first_valid_[camera][static_cast<size_t>(y)]);
    last = std::min(last, last_valid_[camera][static_cast<size_t>(y)]);
  }
  return {first, last};
}

// In canvas pixels: the template centred on (u0, v0), the strip's window
// centres from u0 - max_disparity to u0, both inside the valid columns of
// their rows in their camera.
std::optional<double> StereoRowSearch::Disparity(const cv::Mat& left, const cv::Mat& right,
                                                 const Eigen::Vector2d& uv0_rect_px) const {
  const int half = patch_px_ / 2;
  const int u0 = static_cast<int>(std::lround(uv0_rect_px.x())) - canvas_.x;
  const int v0 = static_cast<int>(std::lround(uv0_rect_px.y())) - canvas_.y;
  if (v0 - half < 0 || v0 + half >= canvas_.height) return std::nullopt;
  const auto [left_first, left_last] = ValidColumns(0, v0 - half, v0 + half);
  if (u0 - half < left_first || u0 + half > left_last) return std::nullopt;
  const auto [right_first, right_last] = ValidColumns(1, v0 - half, v0 + half);
  const int first = std::max(right_first + half, u0 - max_disparity_px_);
  const int last = std::min(right_last - half, u0);
  if (last - first < 2) return std::nullopt;
  const cv::Mat templ = Rectified(0, left, cv::Rect(u0 - half, v0 - half, patch_px_, patch_px_));
  cv::Scalar mean, stddev;
  cv::meanStdDev(templ, mean, stddev);
  if (stddev[0] < kMinPatchStdGrey) return std::nullopt;
  const cv::Rect strip(first - half, v0 - half, last - first + patch_px_, patch_px_);
  const std::vector<float> s = ZnccAlongStrip(Rectified(1, right, strip), templ);
  const int positions = static_cast<int>(s.size());
  const int best = static_cast<int>(std::max_element(s.begin(), s.end()) - s.begin());
  if (s[best] < min_ncc_) return std::nullopt;
  for (int i = 0; i < positions; ++i) {
    if (std::abs(i - best) > kPeakHalfWidthPx && s[i] > s[best] - kUniquenessMargin) return std::nullopt;
  }
  const double offset = best > 0 && best + 1 < positions ? ParabolaVertex(s[best - 1], s[best], s[best + 1]) : 0.0;
  // The template is centred on u0, the best window on first + best + offset.
  const double disparity = u0 - (first + best + offset);
  return disparity > 0.0 ? std::optional<double>(disparity) : std::nullopt;
}

}  // namespace vio::frontend
