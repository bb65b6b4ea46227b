// The KLT front end's shortcuts give exactly what the plain computation
// gives: the grid's cell rectangles (where FAST runs when only some cells need features) are the
// cells Cell() assigns. (frontend_klt_test: per-cell and whole-image
// detection give the same frames.)
#include <vector>

#include <gtest/gtest.h>

#include "vio/frontend/feature_grid.h"

namespace vio::frontend {
namespace {

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
