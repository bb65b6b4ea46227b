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
  const cv::Point2f other(300.0f, 20.0f);
  EXPECT_EQ(failed.Recent(corner), CornerFailure::kNone);
  failed.Remember(corner, CornerFailure::kRowSearch);
  failed.Remember(other, CornerFailure::kStereoMatch);
  // In its own frame (a later round of the same detection), then 3 more.
  for (int frame = 0; frame <= 3; ++frame) {
    EXPECT_EQ(failed.Recent(corner), CornerFailure::kRowSearch) << frame;
    EXPECT_EQ(failed.Recent(corner + cv::Point2f(1.0f, -1.0f)), CornerFailure::kRowSearch) << frame;
    EXPECT_EQ(failed.Recent(corner + cv::Point2f(-1.5f, 1.2f)), CornerFailure::kRowSearch) << frame;
    EXPECT_EQ(failed.Recent(corner + cv::Point2f(6.0f, 0.0f)), CornerFailure::kNone) << frame;
    EXPECT_EQ(failed.Recent(corner + cv::Point2f(0.0f, -6.0f)), CornerFailure::kNone) << frame;
    EXPECT_EQ(failed.Recent(other), CornerFailure::kStereoMatch) << frame;
    failed.NextFrame();
  }
  EXPECT_EQ(failed.Recent(corner), CornerFailure::kNone);
  EXPECT_EQ(failed.Recent(other), CornerFailure::kNone);
}

TEST(FailedCorners, ANewFailureRestartsTheCountAndTheBordersAreClamped) {
  FailedCorners failed(101, 53, 2);
  const cv::Point2f corner(0.0f, 52.9f);
  failed.Remember(corner, CornerFailure::kRowSearch);
  failed.NextFrame();
  failed.Remember(corner, CornerFailure::kStereoMatch);
  failed.NextFrame();
  failed.NextFrame();
  EXPECT_EQ(failed.Recent(corner), CornerFailure::kStereoMatch);
  EXPECT_EQ(failed.Recent(cv::Point2f(-3.0f, 60.0f)), CornerFailure::kStereoMatch);  // outside: the border bin
  failed.NextFrame();
  EXPECT_EQ(failed.Recent(corner), CornerFailure::kNone);
}

TEST(FailedCorners, RejectsBadSizes) {
  EXPECT_THROW(FailedCorners(0, 480, 10), std::invalid_argument);
  EXPECT_THROW(FailedCorners(752, -1, 10), std::invalid_argument);
  EXPECT_THROW(FailedCorners(752, 480, 0), std::invalid_argument);
}

}  // namespace
}  // namespace vio::frontend
