// Tracking loss bookkeeping: which frames count as lost, how losses and their
// durations are counted, and when a loss outlasts the window.
#include <gtest/gtest.h>

#include "vio/estimator/tracking_monitor.h"

namespace vio {
namespace {

constexpr Timestamp kPeriodNs = 50'000'000;

TEST(TrackingMonitor, CountsLossesAndTheirLength) {
  TrackingMonitor monitor(/*min_frame_features=*/10, /*window_size=*/3);
  Timestamp t = 0;
  auto observe = [&](int n) { return monitor.Observe(t += kPeriodNs, n); };
  EXPECT_TRUE(observe(50));
  EXPECT_TRUE(observe(10));
  EXPECT_FALSE(observe(9));  // one frame lost: 100 ms to the next tracked one
  EXPECT_TRUE(observe(40));
  EXPECT_EQ(monitor.report().losses, 1);
  EXPECT_EQ(monitor.report().losses_beyond_window, 0);
  EXPECT_NEAR(monitor.report().longest_loss_s, 0.1, 1e-12);
  for (int k = 0; k < 4; ++k) EXPECT_FALSE(observe(0));  // more than the window of 3
  EXPECT_TRUE(observe(30));
  const TrackingReport& r = monitor.report();
  EXPECT_EQ(r.untracked_frames, 5);
  EXPECT_EQ(r.losses, 2);
  EXPECT_EQ(r.losses_beyond_window, 1);
  EXPECT_NEAR(r.longest_loss_s, 0.25, 1e-12);
}

TEST(TrackingMonitor, LossAtTheStartHasNoLength) {
  TrackingMonitor monitor(5, 10);
  EXPECT_FALSE(monitor.Observe(kPeriodNs, 0));
  EXPECT_TRUE(monitor.Observe(2 * kPeriodNs, 5));
  EXPECT_EQ(monitor.report().losses, 1);
  EXPECT_EQ(monitor.report().longest_loss_s, 0.0);
}

}  // namespace
}  // namespace vio
