#include "vio/estimator/tracking_monitor.h"

#include <algorithm>
#include <iomanip>

#include <glog/logging.h>

namespace vio {

bool TrackingMonitor::Observe(Timestamp t_ns, int observations) {
  if (observations < min_frame_features_) {
    ++report_.untracked_frames;
    if (++lost_frames_ == 1) {
      ++report_.losses;
      LOG(WARNING) << std::fixed << std::setprecision(3) << "tracking lost at t=" << NanosToSeconds(t_ns) << " s: " << observations << " stereo observations < "
                   << min_frame_features_ << " (min_frame_features); propagating on the IMU";
    }
    if (lost_frames_ == window_size_ + 1) {
      ++report_.losses_beyond_window;
      LOG(WARNING) << std::fixed << std::setprecision(3) << "tracking lost for more than the window (" << window_size_ << " frames) at t="
                   << NanosToSeconds(t_ns) << " s: the estimate is IMU dead reckoning until features return";
    }
    return false;
  }
  if (lost_frames_ > 0) {
    const double lost_s = last_tracked_ns_ >= 0 ? NanosToSeconds(t_ns - last_tracked_ns_) : 0.0;
    report_.longest_loss_s = std::max(report_.longest_loss_s, lost_s);
    LOG(WARNING) << std::fixed << std::setprecision(3) << "tracking regained at t=" << NanosToSeconds(t_ns) << " s after " << lost_frames_ << " frames ("
                 << lost_s << " s): new landmarks start from the IMU-propagated pose";
    lost_frames_ = 0;
  }
  last_tracked_ns_ = t_ns;
  return true;
}

}  // namespace vio
