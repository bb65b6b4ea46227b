#pragma once
// Tracking loss: frames with too few stereo observations to constrain the
// pose. Their observations are not used; the state is propagated on the IMU
// (the new state is linked by its IMU factor only). The monitor counts such
// frames and warns when tracking is lost, when the loss outlasts the window
// (every state in it is then IMU dead reckoning from the last tracked one,
// held by the marginalization prior), and when tracking is regained (new
// landmarks start from the propagated pose; the drift of the loss stays).
#include "vio/estimator/types.h"

namespace vio {

/// Counts for summary.json.
struct TrackingReport {
  int untracked_frames = 0;      ///< frames with fewer than min_frame_features observations
  int losses = 0;                ///< runs of such frames
  int losses_beyond_window = 0;  ///< runs longer than the window
  double longest_loss_s = 0.0;   ///< last tracked frame to the frame regaining tracking [s]
};

class TrackingMonitor {
 public:
  TrackingMonitor(int min_frame_features, int window_size)
      : min_frame_features_(min_frame_features), window_size_(window_size) {}

  /// One frame of the initialized estimator with `observations` stereo
  /// observations; true when it is tracked (its observations are used).
  bool Observe(Timestamp t_ns, int observations);

  const TrackingReport& report() const { return report_; }

 private:
  int min_frame_features_;
  int window_size_;
  TrackingReport report_;
  Timestamp last_tracked_ns_ = -1;  ///< -1 before the first tracked frame
  int lost_frames_ = 0;             ///< frames in the current loss
};

}  // namespace vio
