#pragma once
// The two-way index between feature tracks and frames (paper §5.2): for each
// track (= landmark id) the frames it was observed in, for each frame the
// tracks observed in it. Ids are issued here, once per track, increasing,
// never reused.
#include <cstdint>
#include <optional>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "vio/estimator/types.h"

namespace vio::frontend {

class FeatureTracks {
 public:
  /// A fresh landmark id for a new track.
  LandmarkId NewTrack();
  /// Records that `track` (issued by NewTrack) is observed in stereo in frame
  /// `frame`; frames must be recorded in non-decreasing order.
  void Observe(LandmarkId track, std::int64_t frame);

  /// Frames where the track was observed, in order (empty for an unknown id).
  const std::vector<std::int64_t>& FramesOf(LandmarkId track) const;
  /// Tracks observed in a frame, in the order observed (empty when none).
  const std::vector<LandmarkId>& TracksIn(std::int64_t frame) const;

  /// The track's last stereo triangulation in the world, when one was made
  /// with a known camera pose.
  std::optional<Eigen::Vector3d> Position(LandmarkId track) const;
  void SetPosition(LandmarkId track, const Eigen::Vector3d& p_w);

  /// Number of issued tracks.
  std::int64_t num_tracks() const { return next_id_; }
  /// Observation count of every track observed at least once.
  std::vector<int> TrackLengths() const;

 private:
  struct Track {
    std::vector<std::int64_t> frames;
    std::optional<Eigen::Vector3d> p_w;
  };

  std::int64_t next_id_ = 0;
  std::unordered_map<std::int64_t, Track> tracks_;
  std::unordered_map<std::int64_t, std::vector<LandmarkId>> frames_;
};

}  // namespace vio::frontend
