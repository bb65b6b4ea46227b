// FailedCorners: where the KLT detection's corners failed recently, and
// for how long.
#include <stdexcept>

#include <gtest/gtest.h>

#include "vio/frontend/failed_corners.h"

namespace vio::frontend {
namespace {

TEST(FailedCorners, RemembersAFailureNearItsPixelForItsFrames) {
  FailedCorners failed(752, 480, 3);
  failed.NextFrame();
  const cv::Point2f corner(100.4f, 200.7f);
  EXPECT_FALSE(failed.Recent(corner));
  failed.Remember(corner);
  EXPECT_TRUE(failed.Recent(corner));  // in its own frame (a later round of the same detection)
  for (int frame = 1; frame <= 3; ++frame) {
    failed.NextFrame();
    EXPECT_TRUE(failed.Recent(corner)) << frame;
    EXPECT_TRUE(failed.Recent(corner + cv::Point2f(1.0f, -1.0f))) << frame;
    EXPECT_TRUE(failed.Recent(corner + cv::Point2f(-1.5f, 1.2f))) << frame;
    EXPECT_FALSE(failed.Recent(corner + cv::Point2f(6.0f, 0.0f))) << frame;
    EXPECT_FALSE(failed.Recent(corner + cv::Point2f(0.0f, -6.0f))) << frame;
  }
  failed.NextFrame();
  EXPECT_FALSE(failed.Recent(corner));
}

TEST(FailedCorners, ANewFailureRestartsTheCountAndTheBordersAreClamped) {
  FailedCorners failed(101, 53, 2);
  const cv::Point2f corner(0.0f, 52.9f);
  failed.Remember(corner);
  failed.NextFrame();
  failed.Remember(corner);
  failed.NextFrame();
  failed.NextFrame();
  EXPECT_TRUE(failed.Recent(corner));
  EXPECT_TRUE(failed.Recent(cv::Point2f(-3.0f, 60.0f)));  // outside: the border bin
  failed.NextFrame();
  EXPECT_FALSE(failed.Recent(corner));
}

TEST(FailedCorners, RejectsBadSizes) {
  EXPECT_THROW(FailedCorners(0, 480, 10), std::invalid_argument);
  EXPECT_THROW(FailedCorners(752, -1, 10), std::invalid_argument);
  EXPECT_THROW(FailedCorners(752, 480, 0), std::invalid_argument);
}

}  // namespace
}  // namespace vio::frontend
