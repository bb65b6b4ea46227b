#include "vio/frontend/feature_tracks.h"

#include <glog/logging.h>

namespace vio::frontend {

LandmarkId FeatureTracks::NewTrack() {
  const LandmarkId id(next_id_++);
  tracks_[id.value];
  return id;
}

void FeatureTracks::Observe(LandmarkId track, std::int64_t frame) {
  auto it = tracks_.find(track.value);
  CHECK(it != tracks_.end()) << "track " << track.value << " was never issued";
  std::vector<std::int64_t>& frames = it->second.frames;
  CHECK(frames.empty() || frames.back() < frame) << "track " << track.value << " observed twice or out of order";
  frames.push_back(frame);
  frames_[frame].push_back(track);
}

const std::vector<std::int64_t>& FeatureTracks::FramesOf(LandmarkId track) const {
  static const std::vector<std::int64_t> kNone;
  const auto it = tracks_.find(track.value);
  return it == tracks_.end() ? kNone : it->second.frames;
}

const std::vector<LandmarkId>& FeatureTracks::TracksIn(std::int64_t frame) const {
  static const std::vector<LandmarkId> kNone;
  const auto it = frames_.find(frame);
  return it == frames_.end() ? kNone : it->second;
}

std::optional<Eigen::Vector3d> FeatureTracks::Position(LandmarkId track) const {
  const auto it = tracks_.find(track.value);
  return it == tracks_.end() ? std::nullopt : it->second.p_w;
}

void FeatureTracks::SetPosition(LandmarkId track, const Eigen::Vector3d& p_w) {
  auto it = tracks_.find(track.value);
  CHECK(it != tracks_.end()) << "track " << track.value << " was never issued";
  it->second.p_w = p_w;
}

std::vector<int> FeatureTracks::TrackLengths() const {
  std::vector<int> lengths;
  lengths.reserve(tracks_.size());
  for (const auto& [id, track] : tracks_) {
    if (!track.frames.empty()) lengths.push_back(static_cast<int>(track.frames.size()));
  }
  return lengths;
}

}  // namespace vio::frontend
