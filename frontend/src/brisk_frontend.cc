#include "vio/frontend/brisk_frontend.h"

#include <algorithm>
#include <limits>
#include <unordered_map>
#include <unordered_set>

#include <glog/logging.h>

#include "vio/estimator/stereo_geometry.h"
#include "vio/frontend/segment_test_corners.h"

namespace vio::frontend {
namespace {

/// The right image keeps this many times brisk_per_cell keypoints per cell.
constexpr int kRightCellFactor = 3;

Eigen::Vector2d ToEigen(const cv::Point2f& p) { return Eigen::Vector2d(p.x, p.y); }

}  // namespace

BriskFrontend::BriskFrontend(const FrontendOptions& options, const StereoRectifier& rectifier)
    : StereoFrontend(options, rectifier),
      brisk_(cv::BRISK::create(options.brisk_threshold, options.brisk_octaves)),
      grid_(rectifier.camera_model(0).width(), rectifier.camera_model(0).height(), options.grid_cell_px) {}

std::vector<FrameFeature> BriskFrontend::TrackFrame(PreparedPair* pair, const FramePrior& prior) {
  const cv::Mat& left = pair->left;
  const cv::Mat& right = pair->right;
  std::int64_t start = NowNs();
  // The right image keeps more per cell: its cells hold other scene parts
  // (disparity) than the left image's.
  Detections detections[2] = {Detect(left, options().brisk_per_cell),
                              Detect(right, kRightCellFactor * options().brisk_per_cell)};
  Describe(left, std::vector<bool>(detections[0].keypoints.size(), true), &detections[0]);
  AddTime(&StageTimes::detect_ms, start);
  start = NowNs();
  MatchCandidates candidates = StereoCandidates(detections[0], detections[1]);
  // Only right keypoints some left keypoint may match are described.
  std::vector<bool> wanted(detections[1].keypoints.size(), false);
  for (const std::vector<int>& list : candidates) {
    for (int j : list) wanted[static_cast<size_t>(j)] = true;
  }
  AddTime(&StageTimes::stereo_ms, start);
  start = NowNs();
  Describe(right, wanted, &detections[1]);
  AddTime(&StageTimes::detect_ms, start);
  start = NowNs();
  for (std::vector<int>& list : candidates) {
    list.erase(std::remove_if(list.begin(), list.end(),
                              [&](int j) { return !detections[1].described[static_cast<size_t>(j)]; }),
               list.end());
  }
  StereoFeatures current = MatchStereo(detections[0], detections[1], candidates);
  AddTime(&StageTimes::stereo_ms, start);
  start = NowNs();
  MatchTemporal(&current);
  const std::set<LandmarkId> reidentified = Reidentify(prior, &current);
  AddTime(&StageTimes::temporal_ms, start);
  for (FrameFeature& f : current.features) {
    if (!f.tracked) f.id = NewTrack();
  }
  std::vector<FrameFeature> features = current.features;
  const std::vector<LandmarkId> rejected = RejectOutliers(prior, &features);
  CountReidentified(std::count_if(features.begin(), features.end(),
                                  [&](const FrameFeature& f) { return reidentified.count(f.id) > 0; }));
  Remember(current, rejected, prior);
  return features;
}

BriskFrontend::Detections BriskFrontend::Detect(const cv::Mat& image, int per_cell) const {
  std::vector<cv::KeyPoint> all;
  if (options().brisk_octaves > 0) {
    brisk_->detect(image, all);  // multi-scale: BRISK's own scale-space detector
  } else {
    SegmentTestScoreMap scores(image);
    all = DetectSegmentTestCorners(options().brisk_threshold, &scores);
    // Refined before bucketing: the fitted responses rank the corners of a cell
    // (integer scores tie often, and ties would be broken by raster order).
    for (cv::KeyPoint& k : all) RefineCorner(&scores, &k);
  }
  Detections out;
  for (int i : grid_.Bucket(all, per_cell)) out.keypoints.push_back(all[static_cast<size_t>(i)]);
  out.described.assign(out.keypoints.size(), false);
  return out;
}

void BriskFrontend::Describe(const cv::Mat& image, const std::vector<bool>& wanted, Detections* detections) const {
  std::vector<int> index;
  std::vector<cv::KeyPoint> subset;
  for (size_t i = 0; i < wanted.size(); ++i) {
    if (!wanted[i]) continue;
    index.push_back(static_cast<int>(i));
    subset.push_back(detections->keypoints[i]);
  }
  cv::Mat descriptors;
  brisk_->compute(image, subset, descriptors);
  detections->descriptors = cv::Mat::zeros(static_cast<int>(detections->keypoints.size()), brisk_->descriptorSize(),
                                            brisk_->descriptorType());
  detections->described.assign(detections->keypoints.size(), false);
  // compute() keeps the keypoints' order and only drops some (too near the
  // border), so the survivors are found in order.
  size_t next = 0;
  for (int r = 0; r < descriptors.rows; ++r) {
    while (next < index.size() && detections->keypoints[static_cast<size_t>(index[next])].pt != subset[r].pt) ++next;
    CHECK_LT(next, index.size()) << "BRISK returned a keypoint it was not given";
    const int i = index[next++];
    descriptors.row(r).copyTo(detections->descriptors.row(i));
    detections->described[static_cast<size_t>(i)] = true;
  }
}

MatchCandidates BriskFrontend::StereoCandidates(const Detections& left, const Detections& right) const {
  struct Rectified {
    double v, u;
    int index;
  };
  std::vector<Rectified> rows;  // the right keypoints by rectified row
  for (size_t j = 0; j < right.keypoints.size(); ++j) {
    const std::optional<Eigen::Vector2d> uv = rectifier().Rectify(1, ToEigen(right.keypoints[j].pt));
    if (uv) rows.push_back({uv->y(), uv->x(), static_cast<int>(j)});
  }
  std::sort(rows.begin(), rows.end(), [](const Rectified& a, const Rectified& b) { return a.v < b.v; });
  const double band = options().max_epipolar_px;
  MatchCandidates candidates(left.keypoints.size());
  for (size_t i = 0; i < left.keypoints.size(); ++i) {
    if (!left.described[i]) continue;
    const std::optional<Eigen::Vector2d> uv = rectifier().Rectify(0, ToEigen(left.keypoints[i].pt));
    if (!uv) continue;
    auto it = std::lower_bound(rows.begin(), rows.end(), uv->y() - band,
                               [](const Rectified& r, double v) { return r.v < v; });
    for (; it != rows.end() && it->v <= uv->y() + band; ++it) {
      const double disparity = uv->x() - it->u;
      if (disparity > 0.0 && disparity <= options().brisk_max_disparity_px) candidates[i].push_back(it->index);
    }
    std::sort(candidates[i].begin(), candidates[i].end());
  }
  return candidates;
}

BriskFrontend::StereoFeatures BriskFrontend::MatchStereo(const Detections& left, const Detections& right,
                                                         const MatchCandidates& candidates) {
  StereoFeatures out;
  for (const cv::DMatch& m :
       MatchMutualNearest(left.descriptors, right.descriptors, options().max_hamming_bits, &candidates)) {
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
  for (const cv::DMatch& m : MatchMutualNearest(current->left_descriptors, known.left_descriptors, max_bits)) {
    left_match[m.queryIdx] = m.trainIdx;
  }
  for (const cv::DMatch& m : MatchMutualNearest(current->right_descriptors, known.right_descriptors, max_bits)) {
    const auto it = left_match.find(m.queryIdx);
    if (it == left_match.end() || it->second != m.trainIdx) continue;
    FrameFeature& f = current->features[static_cast<size_t>(m.queryIdx)];
    f.id = known.features[static_cast<size_t>(m.trainIdx)].id;
    f.tracked = true;
  }
}

std::set<LandmarkId> BriskFrontend::Reidentify(const FramePrior& prior, StereoFeatures* current) const {
  const double radius = options().reidentify_radius_px;
  std::set<LandmarkId> given;
  if (radius <= 0.0 || !prior.T_w_b || prior.landmarks == nullptr) return given;
  std::set<LandmarkId> recent;  // matched now or tracked in the history: not lost
  for (const FrameFeature& f : current->features) {
    if (f.tracked) recent.insert(f.id);
  }
  for (const StereoFeatures& past : history_) {
    for (const FrameFeature& f : past.features) recent.insert(f.id);
  }
  const RectifiedStereo& stereo = rectifier().rectified();
  const Eigen::Isometry3d T_cl_w = (*prior.T_w_b * stereo.T_b_cl).inverse();
  struct Lost {
    LandmarkId id;
    Eigen::Vector3d z_pred;  // rectified (u_L, u_R, v) in the predicted camera [px]
    const Descriptors* descriptors;
  };
  std::vector<Lost> lost;
  for (const auto& [id, descriptors] : remembered_) {
    const auto it = prior.landmarks->find(id);
    if (recent.count(id) > 0 || it == prior.landmarks->end()) continue;
    const Eigen::Vector3d p_cl = T_cl_w * it->second.position();
    if (p_cl.z() > 0.0) lost.push_back({id, ProjectRectified(p_cl, stereo), &descriptors});
  }
  // Gated pairs by summed Hamming distance; mutual nearest among them.
  constexpr int kNone = std::numeric_limits<int>::max();
  std::vector<int> feature_best(current->features.size(), kNone), lost_best(lost.size(), kNone);
  std::vector<int> feature_match(current->features.size(), -1), lost_match(lost.size(), -1);
  const int max_bits = options().max_hamming_bits;
  for (size_t i = 0; i < current->features.size(); ++i) {
    const FrameFeature& f = current->features[i];
    if (f.tracked) continue;
    for (size_t j = 0; j < lost.size(); ++j) {
      if ((f.z_px - lost[j].z_pred).cwiseAbs().maxCoeff() > radius) continue;
      const int left_bits = static_cast<int>(
          cv::norm(current->left_descriptors.row(static_cast<int>(i)), lost[j].descriptors->left, cv::NORM_HAMMING));
      const int right_bits = static_cast<int>(cv::norm(current->right_descriptors.row(static_cast<int>(i)),
                                                       lost[j].descriptors->right, cv::NORM_HAMMING));
      if (left_bits > max_bits || right_bits > max_bits) continue;
      const int bits = left_bits + right_bits;
      if (bits < feature_best[i]) feature_best[i] = bits, feature_match[i] = static_cast<int>(j);
      if (bits < lost_best[j]) lost_best[j] = bits, lost_match[j] = static_cast<int>(i);
    }
  }
  for (size_t i = 0; i < current->features.size(); ++i) {
    const int j = feature_match[i];
    if (j < 0 || lost_match[static_cast<size_t>(j)] != static_cast<int>(i)) continue;
    FrameFeature& f = current->features[i];
    f.id = lost[static_cast<size_t>(j)].id;
    f.tracked = true;
    given.insert(f.id);
  }
  return given;
}

// The frame, without its rejected matches, joins the history; with
// re-identification on, its features' descriptors replace the remembered
// ones, and only the landmarks the estimator holds or the history saw stay.
void BriskFrontend::Remember(const StereoFeatures& current, const std::vector<LandmarkId>& rejected,
                             const FramePrior& prior) {
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
  if (options().reidentify_radius_px <= 0.0) return;
  const StereoFeatures& newest = history_.front();
  for (size_t i = 0; i < newest.features.size(); ++i) {
    const int row = static_cast<int>(i);
    remembered_[newest.features[i].id] = {newest.left_descriptors.row(row).clone(),
                                          newest.right_descriptors.row(row).clone()};
  }
  std::set<LandmarkId> recent;
  for (const StereoFeatures& past : history_) {
    for (const FrameFeature& f : past.features) recent.insert(f.id);
  }
  for (auto it = remembered_.begin(); it != remembered_.end();) {
    const bool held = prior.landmarks != nullptr && prior.landmarks->count(it->first) > 0;
    it = held || recent.count(it->first) > 0 ? std::next(it) : remembered_.erase(it);
  }
}

}  // namespace vio::frontend
