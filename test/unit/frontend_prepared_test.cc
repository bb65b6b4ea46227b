// The KLT front end's shortcuts give exactly what the plain computation
// gives: RemapBilinear is cv::remap pixel for pixel, and the grid's cell
// rectangles (where FAST runs when only some cells need features) are the
// cells Cell() assigns. (frontend_klt_test: per-cell and whole-image
// detection give the same frames.)
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "vio/frontend/feature_grid.h"
#include "vio/frontend/stereo_row_search.h"

namespace vio::frontend {
namespace {

cv::Mat Noise(cv::Size size, unsigned seed) {
  cv::Mat image(size, CV_8UC1);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(image, image, cv::Size(5, 5), 1.2);
  return image;
}

TEST(RemapBilinear, EqualsCvRemapIncludingTheBorders) {
  const cv::Mat src = Noise(cv::Size(60, 40), 3);
  std::mt19937 rng(5);
  // Positions inside, on the last row and column, partly and wholly outside,
  // and whole pixels (fraction 0).
  std::uniform_real_distribution<float> u(-3.0f, 63.0f), v(-3.0f, 43.0f);
  std::uniform_int_distribution<int> whole_u(-2, 61), whole_v(-2, 41);
  cv::Mat map_x(50, 70, CV_32FC1), map_y(50, 70, CV_32FC1);
  for (int y = 0; y < map_x.rows; ++y) {
    for (int x = 0; x < map_x.cols; ++x) {
      const bool whole = (x + y) % 5 == 0;
      map_x.at<float>(y, x) = whole ? static_cast<float>(whole_u(rng)) : u(rng);
      map_y.at<float>(y, x) = whole ? static_cast<float>(whole_v(rng)) : v(rng);
    }
  }
  cv::Mat map_xy, map_frac, expected;
  cv::convertMaps(map_x, map_y, map_xy, map_frac, CV_16SC2);
  cv::remap(src, expected, map_xy, map_frac, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  cv::Mat got(map_xy.size(), CV_8UC1);
  RemapBilinear(src, map_xy, map_frac, &got);
  EXPECT_EQ(cv::countNonZero(got != expected), 0);
  // On a region of the maps, as the row search uses them.
  const cv::Rect roi(7, 9, 31, 11);
  cv::Mat part(roi.size(), CV_8UC1);
  RemapBilinear(src, map_xy(roi), map_frac(roi), &part);
  EXPECT_EQ(cv::countNonZero(part != expected(roi)), 0);
}

TEST(FeatureGrid, CellRectsTileTheImageAsCellDoes) {
  const FeatureGrid grid(101, 53, 12.5);
  std::vector<int> seen(static_cast<size_t>(grid.num_cells()), 0);
  for (int y = 0; y < 53; ++y) {
    for (int x = 0; x < 101; ++x) {
      const int cell = grid.Cell(cv::Point2f(static_cast<float>(x), static_cast<float>(y)));
      ASSERT_TRUE(grid.CellRect(cell).contains(cv::Point(x, y))) << x << " " << y;
      ++seen[static_cast<size_t>(cell)];
    }
  }
  for (int c = 0; c < grid.num_cells(); ++c) EXPECT_EQ(seen[static_cast<size_t>(c)], grid.CellRect(c).area());
}

}  // namespace
}  // namespace vio::frontend
