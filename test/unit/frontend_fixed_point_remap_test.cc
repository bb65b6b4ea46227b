// RemapLinear (fixed_point_remap.h) gives cv::remap's pixels: bilinear
// interpolation through fixed-point maps with a constant 0 border, inside the
// image, across its last row and column, partly and wholly outside it.
#include <random>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "vio/frontend/fixed_point_remap.h"

namespace vio::frontend {
namespace {

cv::Mat RandomImage(int cols, int rows, std::mt19937* rng) {
  cv::Mat image(rows, cols, CV_8UC1);
  std::uniform_int_distribution<int> grey(0, 255);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) image.at<uchar>(r, c) = static_cast<uchar>(grey(*rng));
  }
  return image;
}

// Float maps over [lo, hi) in x and y, as cv::convertMaps makes fixed-point ones.
std::pair<cv::Mat, cv::Mat> FixedPointMaps(int cols, int rows, float lo_x, float hi_x, float lo_y, float hi_y,
                                           std::mt19937* rng) {
  cv::Mat map_x(rows, cols, CV_32FC1), map_y(rows, cols, CV_32FC1);
  std::uniform_real_distribution<float> x(lo_x, hi_x), y(lo_y, hi_y);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      map_x.at<float>(r, c) = x(*rng);
      map_y.at<float>(r, c) = y(*rng);
    }
  }
  cv::Mat xy, frac;
  cv::convertMaps(map_x, map_y, xy, frac, CV_16SC2);
  return {xy, frac};
}

void ExpectSameAsOpenCv(const cv::Mat& src, const cv::Mat& xy, const cv::Mat& frac) {
  cv::Mat expected, actual;
  cv::remap(src, expected, xy, frac, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  RemapLinear(src, xy, frac, &actual);
  ASSERT_EQ(actual.type(), CV_8UC1);
  ASSERT_EQ(actual.size(), expected.size());
  EXPECT_EQ(cv::norm(actual, expected, cv::NORM_INF), 0.0);
}

TEST(RemapLinear, EqualsOpenCvInsideTheImage) {
  std::mt19937 rng(1);
  const cv::Mat src = RandomImage(60, 40, &rng);
  const auto [xy, frac] = FixedPointMaps(50, 30, 0.0f, 58.99f, 0.0f, 38.99f, &rng);
  ExpectSameAsOpenCv(src, xy, frac);
}

TEST(RemapLinear, EqualsOpenCvAcrossTheBorderAndOutside) {
  std::mt19937 rng(2);
  const cv::Mat src = RandomImage(30, 20, &rng);
  const auto [xy, frac] = FixedPointMaps(80, 60, -3.0f, 33.0f, -3.0f, 23.0f, &rng);
  ExpectSameAsOpenCv(src, xy, frac);
}

TEST(RemapLinear, EqualsOpenCvOnSubMatrices) {
  std::mt19937 rng(3);
  const cv::Mat src = RandomImage(64, 48, &rng);
  const auto [xy, frac] = FixedPointMaps(40, 40, -1.0f, 64.5f, -1.0f, 48.5f, &rng);
  const cv::Rect roi(7, 5, 13, 11);
  ExpectSameAsOpenCv(src(cv::Rect(3, 2, 50, 40)), xy(roi), frac(roi));
}

TEST(RemapLinear, WholePixelsCopyTheSource) {
  std::mt19937 rng(4);
  const cv::Mat src = RandomImage(16, 12, &rng);
  cv::Mat map_x(12, 16, CV_32FC1), map_y(12, 16, CV_32FC1);
  for (int r = 0; r < 12; ++r) {
    for (int c = 0; c < 16; ++c) map_x.at<float>(r, c) = static_cast<float>(c), map_y.at<float>(r, c) = static_cast<float>(r);
  }
  cv::Mat xy, frac, out;
  cv::convertMaps(map_x, map_y, xy, frac, CV_16SC2);
  RemapLinear(src, xy, frac, &out);
  EXPECT_EQ(cv::norm(out, src, cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace vio::frontend
