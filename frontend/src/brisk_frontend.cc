#include "vio/frontend/brisk_frontend.h"

#include <algorithm>
#include <unordered_map>
#include <unordered_set>

namespace vio::frontend {
namespace {

/// The right image keeps this many times brisk_per_cell keypoints per cell.
constexpr int kRightCellFactor = 3;

// Cross-checked brute-force matches query -> train no further than max_bits.
std::vector<cv::DMatch> MatchHamming(const cv::BFMatcher& matcher, const cv::Mat& query, const cv::Mat& train,
                                     int max_bits) {
  std::vector<cv::DMatch> matches;
  if (query.empty() || train.empty()) return matches;
  matcher.match(query, train, matches);
  matches.erase(std::remove_if(matches.begin(), matches.end(),
                               [&](const cv::DMatch& m) { return m.distance > static_cast<float>(max_bits); }),
                matches.end());
  return matches;
}

Eigen::Vector2d ToEigen(const cv::Point2f& p) { return Eigen::Vector2d(p.x, p.y); }

}  // namespace

BriskFrontend::BriskFrontend(const FrontendOptions& options, const StereoRectifier& rectifier)
    : StereoFrontend(options, rectifier),
      brisk_(cv::BRISK::create(options.brisk_threshold, options.brisk_octaves)),
      matcher_(cv::NORM_HAMMING, /*crossCheck=*/true),
      grid_(rectifier.camera_model(0).width(), rectifier.camera_model(0).height(), options.grid_cell_px) {}

std::vector<FrameFeature> BriskFrontend::TrackFrame(const cv::Mat& left, const cv::Mat& right,
                                                    const FramePrior& prior) {
  std::int64_t start = NowNs();
  // The right image keeps more per cell: its cells hold other scene parts
  // (disparity) than the left image's.
  const Detections detections[2] = {Detect(left, options().brisk_per_cell),
                                    Detect(right, kRightCellFactor * options().brisk_per_cell)};
  AddTime(&StageTimes::detect_ms, start);
  start = NowNs();
  StereoFeatures current = MatchStereo(detections[0], detections[1]);
  AddTime(&StageTimes::stereo_ms, start);
  start = NowNs();
  MatchTemporal(&current);
  AddTime(&StageTimes::temporal_ms, start);
  for (FrameFeature& f : current.features) {
    if (!f.tracked) f.id = NewTrack();
  }
  std::vector<FrameFeature> features = current.features;
  const std::vector<LandmarkId> rejected = RejectOutliers(prior, &features);
  Remember(current, rejected);
  return features;
}

BriskFrontend::Detections BriskFrontend::Detect(const cv::Mat& image, int per_cell) const {
  std::vector<cv::KeyPoint> all;
  brisk_->detect(image, all);
  Detections out;
  for (int i : grid_.Bucket(all, per_cell)) out.keypoints.push_back(all[static_cast<size_t>(i)]);
  brisk_->compute(image, out.keypoints, out.descriptors);
  return out;
}

BriskFrontend::StereoFeatures BriskFrontend::MatchStereo(const Detections& left, const Detections& right) {
  StereoFeatures out;
  for (const cv::DMatch& m : MatchHamming(matcher_, left.descriptors, right.descriptors, options().max_hamming_bits)) {
    const Eigen::Vector2d uv0 = ToEigen(left.keypoints[static_cast<size_t>(m.queryIdx)].pt);
    const Eigen::Vector2d uv1 = ToEigen(right.keypoints[static_cast<size_t>(m.trainIdx)].pt);
    const std::optional<Eigen::Vector3d> z = StereoMeasurement(uv0, uv1);
    if (!z) continue;
    FrameFeature f;
    f.uv0_px = uv0;
    f.uv1_px = uv1;
    f.z_px = *z;
    f.stereo = true;
    out.features.push_back(f);
    out.left_descriptors.push_back(left.descriptors.row(m.queryIdx));
    out.right_descriptors.push_back(right.descriptors.row(m.trainIdx));
  }
  return out;
}

// Four-way check: feature i continues track j only when its left descriptor
// matches j's left one AND its right descriptor matches j's right one.
void BriskFrontend::MatchTemporal(StereoFeatures* current) const {
  StereoFeatures known;  // newest observation of every track in the history
  std::unordered_set<std::int64_t> seen;
  for (const StereoFeatures& past : history_) {
    for (size_t i = 0; i < past.features.size(); ++i) {
      if (!seen.insert(past.features[i].id.value).second) continue;
      known.features.push_back(past.features[i]);
      known.left_descriptors.push_back(past.left_descriptors.row(static_cast<int>(i)));
      known.right_descriptors.push_back(past.right_descriptors.row(static_cast<int>(i)));
    }
  }
  const int max_bits = options().max_hamming_bits;
  std::unordered_map<int, int> left_match;  // current feature -> known track index
  for (const cv::DMatch& m : MatchHamming(matcher_, current->left_descriptors, known.left_descriptors, max_bits)) {
    left_match[m.queryIdx] = m.trainIdx;
  }
  for (const cv::DMatch& m : MatchHamming(matcher_, current->right_descriptors, known.right_descriptors, max_bits)) {
    const auto it = left_match.find(m.queryIdx);
    if (it == left_match.end() || it->second != m.trainIdx) continue;
    FrameFeature& f = current->features[static_cast<size_t>(m.queryIdx)];
    f.id = known.features[static_cast<size_t>(m.trainIdx)].id;
    f.tracked = true;
  }
}

// The frame, without its rejected matches, joins the history.
void BriskFrontend::Remember(const StereoFeatures& current, const std::vector<LandmarkId>& rejected) {
  const std::unordered_set<std::int64_t> dropped = [&] {
    std::unordered_set<std::int64_t> ids;
    for (LandmarkId id : rejected) ids.insert(id.value);
    return ids;
  }();
  StereoFeatures kept;
  for (size_t i = 0; i < current.features.size(); ++i) {
    const FrameFeature& f = current.features[i];
    if (f.tracked && dropped.count(f.id.value)) continue;
    kept.features.push_back(f);
    kept.left_descriptors.push_back(current.left_descriptors.row(static_cast<int>(i)));
    kept.right_descriptors.push_back(current.right_descriptors.row(static_cast<int>(i)));
  }
  history_.push_front(std::move(kept));
  while (history_.size() > static_cast<size_t>(options().track_window_frames)) history_.pop_back();
}

}  // namespace vio::frontend
