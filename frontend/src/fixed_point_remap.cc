#include "vio/frontend/fixed_point_remap.h"

#include <array>
#include <cstdint>

#include <glog/logging.h>
#include <opencv2/imgproc.hpp>

namespace vio::frontend {
namespace {

constexpr int kTable = cv::INTER_TAB_SIZE;                // fractions per pixel (32)
constexpr int kCoefficientBits = 15;                      // weights sum to 2^15 (OpenCV's INTER_REMAP_COEF_BITS)

// cv::remap's weights per fraction index fy * 32 + fx: (1 - y)(1 - x), (1 - y) x,
// y (1 - x), y x times 2^15, exact in its float computation (multiples of 1/1024),
// so no rounding correction applies.
struct Weights {
  std::array<std::array<int, 4>, kTable * kTable> w{};
  Weights() {
    const int scale = (1 << kCoefficientBits) / (kTable * kTable);
    for (int fy = 0; fy < kTable; ++fy) {
      for (int fx = 0; fx < kTable; ++fx) {
        w[static_cast<size_t>(fy * kTable + fx)] = {scale * (kTable - fy) * (kTable - fx), scale * (kTable - fy) * fx,
                                                    scale * fy * (kTable - fx), scale * fy * fx};
      }
    }
  }
};

// The source pixel, 0 outside (BORDER_CONSTANT).
int At(const cv::Mat& src, int x, int y) {
  return x >= 0 && y >= 0 && x < src.cols && y < src.rows ? src.at<uchar>(y, x) : 0;
}

}  // namespace

void RemapLinear(const cv::Mat& src, const cv::Mat& map_xy, const cv::Mat& map_frac, cv::Mat* dst) {
  CHECK_EQ(src.type(), CV_8UC1);
  CHECK_EQ(map_xy.type(), CV_16SC2);
  CHECK_EQ(map_frac.type(), CV_16UC1);
  CHECK(map_xy.size() == map_frac.size());
  static const Weights table;
  dst->create(map_xy.size(), CV_8UC1);
  // Locals: the uchar stores below may alias anything, which would make the
  // compiler reload members every pixel.
  const int rounding = 1 << (kCoefficientBits - 1);
  const auto step = static_cast<std::ptrdiff_t>(src.step);
  const uchar* const data = src.data;
  const auto last_x = static_cast<unsigned>(src.cols - 1), last_y = static_cast<unsigned>(src.rows - 1);
  const std::array<int, 4>* const weights = table.w.data();
  for (int r = 0; r < map_xy.rows; ++r) {
    const std::int16_t* xy = map_xy.ptr<std::int16_t>(r);
    const std::uint16_t* frac = map_frac.ptr<std::uint16_t>(r);
    uchar* out = dst->ptr<uchar>(r);
    const int cols = map_xy.cols;
    for (int c = 0; c < cols; ++c) {
      const int x = xy[2 * c], y = xy[2 * c + 1];
      const std::array<int, 4>& w = weights[frac[c] & (kTable * kTable - 1)];
      int sum;
      if (static_cast<unsigned>(x) < last_x && static_cast<unsigned>(y) < last_y) {
        const uchar* p = data + y * step + x;
        sum = p[0] * w[0] + p[1] * w[1] + p[step] * w[2] + p[step + 1] * w[3];
      } else if (x > static_cast<int>(last_x) || x + 1 < 0 || y > static_cast<int>(last_y) || y + 1 < 0) {
        sum = 0;
      } else {
        sum = At(src, x, y) * w[0] + At(src, x + 1, y) * w[1] + At(src, x, y + 1) * w[2] +
              At(src, x + 1, y + 1) * w[3];
      }
      out[c] = static_cast<uchar>((sum + rounding) >> kCoefficientBits);
    }
  }
}

}  // namespace vio::frontend
