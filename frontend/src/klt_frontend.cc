#include "vio/frontend/klt_frontend.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_set>

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

namespace vio::frontend {
namespace {

/// A row-search disparity this close to the one LK already failed from is
/// not tried again [px].
constexpr double kSameSeedPx = 1.0;
/// Side of the row search's patch [px].
constexpr int kRowSearchPatchPx = 11;
/// Corners tried by the row search per grid cell and frame, per feature the
/// cell still wants [count].
constexpr int kSearchesPerWantedFeature = 2;
/// Pyramid levels of the left -> right LK: its seeds (the last or the
/// row-search disparity) are within a few pixels, and coarser levels, which
/// see a wide neighbourhood, are misled where the two views differ most
/// (the slanted near floor, occluding edges) [count].
constexpr int kStereoPyramidLevels = 0;
/// New corners are sought only when at least this fraction of
/// klt_max_features is missing: FAST and the sort of its corners cost about
/// 2 ms on a 752x480 frame, and a handful of lost features is refilled a few
/// frames later (0.05 on the rendered V2_01: 296 -> 290 stereo features per
/// frame, detection 2.1 -> 0.8 ms per frame).
constexpr double kMinMissingFraction = 0.05;
/// Pyramid levels of the temporal LK from an IMU-predicted pixel, which is
/// within a few pixels unless the prediction is bad (then the track is
/// retried from its previous pixel over klt_pyramid_levels): the full image
/// alone, whose 15 px window already reaches 7 px. On the rendered V2_01,
/// V1_02 and MH_04 (20 s each), 284 of 285 predicted tracks per frame are
/// kept either way; one level instead of two cut the front end's CPU time
/// by a quarter, and the ATE, averaged over four klt_max_fb_px values
/// (0.97-1.03) per sequence, moved by +4, -6, -9 % (MSCKF(10)) and -4,
/// -2.5, -2 % (SWF(10)) [count].
constexpr int kPredictedPyramidLevels = 0;
/// TrackPoints' agree_px that always checks backward [px].
constexpr double kNoAgreement = -1.0;
/// A forward LK that ends this close to a seed of its own evidence (a
/// temporal track's IMU-predicted pixel, a stereo track's last disparity)
/// is kept without the backward LK: two sources agree. Not for seeds that
/// are only a guess (no prediction: the previous pixel) or come from the
/// row search. On the rendered V2_01, V1_02, MH_04 (20 s, KLT + MSCKF(10),
/// mean ATE over five klt_max_fb_px values) 0.01112, 0.01569, 0.00388 m
/// with the backward LK always, 0.01087, 0.01644, 0.00379 m with this;
/// the LK's instructions on the still real clip fall by 22 % [px].
constexpr double kSeedAgreementPx = 0.3;
/// Features unmatched left-right for more consecutive frames are dropped.
constexpr int kMaxFramesWithoutStereo = 3;
FrontendOptions Checked(const FrontendOptions& options) {
  if (options.klt_max_features <= 0) throw std::invalid_argument("front end options: klt_max_features must be > 0");
  return options;
}

}  // namespace

bool KltFrontend::Inside(const cv::Point2f& p, const cv::Mat& image) {
  return p.x >= 0 && p.y >= 0 && p.x <= static_cast<float>(image.cols - 1) &&
         p.y <= static_cast<float>(image.rows - 1);
}

KltFrontend::KltFrontend(const FrontendOptions& options, const StereoRectifier& rectifier)
    : StereoFrontend(Checked(options), rectifier),
      grid_(rectifier.camera_model(0).width(), rectifier.camera_model(0).height(), options.grid_cell_px),
      row_search_(rectifier, kRowSearchPatchPx, options.klt_max_disparity_px, options.klt_min_ncc),
      failed_corners_(rectifier.camera_model(0).width(), rectifier.camera_model(0).height(),
                      FailedCorners::kKltFrames) {}

// The pyramids (the left one over klt_pyramid_levels for the temporal LK,
// the right one at full resolution for the stereo LK) are built once here
// and serve every LK of the frame; the left one is the next frame's
// previous pyramid.
void KltFrontend::PrepareImages(bool with_corners, PreparedPair* pair) const {
  const cv::Size window(options().klt_window_px, options().klt_window_px);
  cv::buildOpticalFlowPyramid(pair->left, pair->left_pyramid, window, options().klt_pyramid_levels);
  cv::buildOpticalFlowPyramid(pair->right, pair->right_pyramid, window, kStereoPyramidLevels);
  if (with_corners) {
    cv::FAST(pair->left, pair->corners, options().klt_fast_threshold, /*nonmaxSuppression=*/true);
    pair->corners_ready = true;
  }
}

std::vector<FrameFeature> KltFrontend::TrackFrame(PreparedPair* pair, const FramePrior& prior) {
  std::int64_t start = NowNs();
  failed_corners_.NextFrame();
  TrackTemporal(pair->left_pyramid, prior);
  AddTime(&StageTimes::temporal_ms, start);
  start = NowNs();
  const StereoImages images{pair->left, pair->right, pair->left_pyramid, pair->right_pyramid};
  MatchTracks(images);
  AddTime(&StageTimes::stereo_ms, start);
  start = NowNs();
  Thin(pair->left);
  AddTime(&StageTimes::detect_ms, start);
  start = NowNs();
  const std::set<LandmarkId> reidentified = Reidentify(images, prior, &mask_, &per_cell_);
  AddTime(&StageTimes::temporal_ms, start);
  start = NowNs();
  DetectNew(images, *pair);
  AddTime(&StageTimes::detect_ms, start);
  std::vector<FrameFeature> features = Features();
  DropTracks(RejectOutliers(prior, &features));
  CountReidentified(std::count_if(features.begin(), features.end(),
                                  [&](const FrameFeature& f) { return reidentified.count(f.id) > 0; }));
  Remember(prior);
  // The pair takes the buffers of the pyramid before: Prepare refills them.
  std::swap(previous_left_, pair->left_pyramid);
  return features;
}

void KltFrontend::DropTracks(const std::vector<LandmarkId>& rejected) {
  std::unordered_set<std::int64_t> dropped;
  for (LandmarkId id : rejected) dropped.insert(id.value);
  tracks_.erase(std::remove_if(tracks_.begin(), tracks_.end(),
                               [&](const Track& t) { return dropped.count(t.id.value) > 0; }),
                tracks_.end());
}

std::vector<bool> KltFrontend::TrackPoints(const std::vector<cv::Mat>& from, const std::vector<cv::Mat>& to,
                                           const std::vector<cv::Point2f>& points,
                                           std::vector<cv::Point2f>* guess, int levels, double agree_px) const {
  std::vector<bool> kept(points.size(), false);
  if (points.empty()) return kept;
  const cv::Size window(options().klt_window_px, options().klt_window_px);
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.01);
  std::vector<uchar> status, back_status;
  const std::vector<cv::Point2f> seeds = *guess;
  // No error output: OpenCV then skips the extra pass over each window that
  // computes it.
  cv::calcOpticalFlowPyrLK(from, to, points, *guess, status, cv::noArray(), window, levels, criteria,
                           cv::OPTFLOW_USE_INITIAL_FLOW);
  std::vector<size_t> check;
  std::vector<cv::Point2f> forward, back;
  for (size_t i = 0; i < points.size(); ++i) {
    if (!status[i] || !Inside((*guess)[i], to[0])) continue;
    if (cv::norm((*guess)[i] - seeds[i]) <= agree_px) {
      kept[i] = true;
      continue;
    }
    check.push_back(i);
    forward.push_back((*guess)[i]);
    back.push_back(points[i]);
  }
  if (check.empty()) return kept;
  cv::calcOpticalFlowPyrLK(to, from, forward, back, back_status, cv::noArray(), window, levels, criteria,
                           cv::OPTFLOW_USE_INITIAL_FLOW);
  const double max_fb = options().klt_max_fb_px;
  for (size_t j = 0; j < check.size(); ++j) {
    kept[check[j]] = back_status[j] && cv::norm(back[j] - points[check[j]]) <= max_fb;
  }
  return kept;
}

// Tracks with a predicted pixel first, from there over kPredictedPyramidLevels;
// the others, and those that fail, from their previous pixel over the whole
// pyramid.
void KltFrontend::TrackTemporal(const std::vector<cv::Mat>& left, const FramePrior& prior) {
  for (Track& t : tracks_) t.tracked = false;
  if (previous_left_.empty() || tracks_.empty()) return;
  std::vector<size_t> predicted, rest;
  std::vector<cv::Point2f> guesses;
  for (size_t i = 0; i < tracks_.size(); ++i) {
    const std::optional<cv::Point2f> guess = PredictedPixel(tracks_[i].id, prior);
    (guess ? predicted : rest).push_back(i);
    if (guess) guesses.push_back(*guess);
  }
  std::vector<bool> kept(tracks_.size(), false);
  std::vector<cv::Point2f> moved(tracks_.size());
  TrackSome(left, predicted, guesses, kPredictedPyramidLevels, kSeedAgreementPx, &kept, &moved);
  for (size_t i : predicted) {
    if (!kept[i]) rest.push_back(i);
  }
  guesses.clear();
  for (size_t i : rest) guesses.push_back(tracks_[i].uv0_px);
  TrackSome(left, rest, guesses, options().klt_pyramid_levels, kNoAgreement, &kept, &moved);
  std::vector<Track> survivors;
  for (size_t i = 0; i < tracks_.size(); ++i) {
    if (!kept[i]) continue;
    Track t = tracks_[i];
    t.uv0_px = moved[i];
    t.tracked = true;
    ++t.age;
    survivors.push_back(t);
  }
  tracks_ = std::move(survivors);
}

void KltFrontend::TrackSome(const std::vector<cv::Mat>& left, const std::vector<size_t>& which,
                            std::vector<cv::Point2f> guesses, int levels, double agree_px, std::vector<bool>* kept,
                            std::vector<cv::Point2f>* moved) const {
  std::vector<cv::Point2f> points;
  for (size_t i : which) points.push_back(tracks_[i].uv0_px);
  const std::vector<bool> ok = TrackPoints(previous_left_, left, points, &guesses, levels, agree_px);
  for (size_t j = 0; j < which.size(); ++j) {
    (*kept)[which[j]] = ok[j];
    (*moved)[which[j]] = guesses[j];
  }
}

// The landmark (the window's estimate, else the track's own triangulation)
// seen from the predicted pose.
std::optional<cv::Point2f> KltFrontend::PredictedPixel(LandmarkId id, const FramePrior& prior) const {
  if (!prior.T_w_b) return std::nullopt;
  const std::optional<Eigen::Vector3d> p_w = LandmarkPosition(id, prior);
  if (!p_w) return std::nullopt;
  return LeftPixel(*p_w, *prior.T_w_b);
}

// The point in the rectified left camera, then in the raw left image.
std::optional<cv::Point2f> KltFrontend::LeftPixel(const Eigen::Vector3d& p_w, const Eigen::Isometry3d& T_w_b) const {
  const RectifiedStereo& stereo = rectifier().rectified();
  const Eigen::Vector3d p_cl = (T_w_b * stereo.T_b_cl).inverse() * p_w;
  if (p_cl.z() <= 0.0) return std::nullopt;
  const std::optional<Eigen::Vector2d> uv =
      rectifier().camera_model(0).Project(rectifier().R_rect_cam(0).transpose() * p_cl);
  if (!uv) return std::nullopt;
  return cv::Point2f(static_cast<float>(uv->x()), static_cast<float>(uv->y()));
}

// LK from the last disparity; the tracks it fails for, from the row search's
// disparity when that is a different seed.
void KltFrontend::MatchTracks(const StereoImages& images) {
  std::vector<Track*> all;
  for (Track& t : tracks_) {
    t.match.reset();
    all.push_back(&t);
  }
  MatchAt(images, all, kSeedAgreementPx);
  std::vector<Track*> retry;
  for (Track& t : tracks_) {
    if (t.match) continue;
    const std::optional<double> d = SearchRow(images, t.uv0_px);
    if (!d || std::abs(*d - t.disparity_px) < kSameSeedPx) continue;
    t.disparity_px = *d;
    retry.push_back(&t);
  }
  MatchAt(images, retry, kNoAgreement);
}

std::optional<double> KltFrontend::SearchRow(const StereoImages& images, const cv::Point2f& uv0_px) {
  CountRowSearch();
  const std::optional<Eigen::Vector2d> rect = rectifier().Rectify(0, Eigen::Vector2d(uv0_px.x, uv0_px.y));
  if (!rect) return std::nullopt;
  return row_search_.Disparity(images.left, images.right, *rect);
}

// LK from the right pixel at each track's disparity, forward-backward
// checked, then the epipolar check.
void KltFrontend::MatchAt(const StereoImages& images, const std::vector<Track*>& tracks, double agree_px) {
  std::vector<cv::Point2f> points, matched;
  for (const Track* t : tracks) {
    points.push_back(t->uv0_px);
    matched.push_back(RightPixelAt(t->uv0_px, t->disparity_px));
  }
  const std::vector<bool> kept = TrackPoints(images.left_pyramid, images.right_pyramid, points, &matched,
                                             kStereoPyramidLevels, agree_px);
  for (size_t j = 0; j < tracks.size(); ++j) {
    if (!kept[j]) continue;
    const Eigen::Vector2d uv1(matched[j].x, matched[j].y);
    const std::optional<Eigen::Vector3d> z = StereoMeasurement(Eigen::Vector2d(points[j].x, points[j].y), uv1);
    if (z) tracks[j]->match = StereoMatch{uv1, *z};
  }
}

cv::Point2f KltFrontend::RightPixelAt(const cv::Point2f& uv0_px, double disparity_px) const {
  const std::optional<Eigen::Vector2d> left = rectifier().Rectify(0, Eigen::Vector2d(uv0_px.x, uv0_px.y));
  if (!left) return uv0_px;
  const RectifiedStereo& r = rectifier().rectified();
  const Eigen::Vector3d ray_rect((left->x() - disparity_px - r.cx) / r.f, (left->y() - r.cy) / r.f, 1.0);
  const std::optional<Eigen::Vector2d> uv1 =
      rectifier().camera_model(1).ProjectUnbounded(rectifier().R_rect_cam(1).transpose() * ray_rect);
  return uv1 ? cv::Point2f(static_cast<float>(uv1->x()), static_cast<float>(uv1->y())) : uv0_px;
}

void KltFrontend::Thin(const cv::Mat& left) {
  for (Track& t : tracks_) t.frames_without_stereo = t.match ? 0 : t.frames_without_stereo + 1;
  std::stable_sort(tracks_.begin(), tracks_.end(), [](const Track& a, const Track& b) { return a.age > b.age; });
  per_cell_.assign(static_cast<size_t>(grid_.num_cells()), 0);
  mask_.create(left.size(), CV_8UC1);
  mask_.setTo(cv::Scalar(255));
  cv::Mat& mask = mask_;
  const int radius = static_cast<int>(options().klt_min_distance_px);
  std::vector<Track> kept;
  for (const Track& t : tracks_) {
    int& n = per_cell_[static_cast<size_t>(grid_.Cell(t.uv0_px))];
    const cv::Point pixel(cvRound(t.uv0_px.x), cvRound(t.uv0_px.y));
    if (t.frames_without_stereo > kMaxFramesWithoutStereo || n >= options().klt_per_cell ||
        mask.at<uchar>(pixel) == 0) {
      continue;
    }
    ++n;
    cv::circle(mask, pixel, radius, cv::Scalar(0), cv::FILLED);
    kept.push_back(t);
  }
  tracks_ = std::move(kept);
}

// Candidates are stereo-matched at once; only the matched ones become
// features (and get an id).
void KltFrontend::DetectNew(const StereoImages& images, const PreparedPair& pair) {
  std::vector<Track> candidates = Candidates(images, pair);
  std::vector<Track*> pointers;
  for (Track& t : candidates) pointers.push_back(&t);
  MatchAt(images, pointers, kNoAgreement);
  for (Track& t : candidates) {
    if (!t.match) {
      failed_corners_.Remember(t.uv0_px, CornerFailure::kStereoMatch);
      continue;
    }
    t.id = NewTrack();
    tracks_.push_back(t);
  }
}

// FAST corners strongest first, in rounds: round r gives each cell holding
// fewer than r features one more, up to klt_per_cell per cell and
// klt_max_features in all (none while fewer than kMinMissingFraction of them
// are missing); a corner must be klt_min_distance_px from every
// feature and found by the row search (at most kSearchesPerWantedFeature
// tries per wanted feature and cell). A corner near one that failed in the
// last FailedCorners::kKltFrames frames (failed_corners_) fails as that one
// did without a row search or LK: it uses the cell's budget, and when that
// one failed in the stereo LK it also takes its place in the cell and the
// mask, as it would if tried again on the same images.
std::vector<KltFrontend::Track> KltFrontend::Candidates(const StereoImages& images, const PreparedPair& pair) {
  std::vector<int>& per_cell = per_cell_;
  const int per_cell_max = options().klt_per_cell;
  const int wanted = options().klt_max_features - static_cast<int>(tracks_.size());
  std::vector<Track> candidates;
  const bool open = std::any_of(per_cell.begin(), per_cell.end(), [&](int n) { return n < per_cell_max; });
  if (!open || wanted < kMinMissingFraction * options().klt_max_features) {
    return candidates;
  }
  const std::vector<cv::KeyPoint>& corners = OpenCellCorners(pair);
  std::vector<int> searches(per_cell.size(), 0);
  std::vector<int> search_budget(per_cell.size());
  for (size_t c = 0; c < per_cell.size(); ++c) {
    search_budget[c] = kSearchesPerWantedFeature * std::max(0, per_cell_max - per_cell[c]);
  }
  const int radius = static_cast<int>(options().klt_min_distance_px);
  int taken = 0;  // candidates, and the corners standing for one that failed in stereo
  for (int round = 1; round <= per_cell_max; ++round) {
    for (const cv::KeyPoint& corner : corners) {
      if (taken >= wanted) return candidates;
      const auto cell = static_cast<size_t>(grid_.Cell(corner.pt));
      const cv::Point pixel(cvRound(corner.pt.x), cvRound(corner.pt.y));
      if (per_cell[cell] >= round || searches[cell] >= search_budget[cell] || mask_.at<uchar>(pixel) == 0) {
        continue;
      }
      ++searches[cell];
      // A corner that failed here recently fails as it did, without trying.
      const CornerFailure failed = failed_corners_.Recent(corner.pt);
      if (failed == CornerFailure::kRowSearch) continue;
      const std::optional<double> disparity =
          failed == CornerFailure::kNone ? SearchRow(images, corner.pt) : std::optional<double>(0.0);
      if (!disparity) {
        failed_corners_.Remember(corner.pt, CornerFailure::kRowSearch);
        continue;
      }
      ++per_cell[cell];
      ++taken;
      cv::circle(mask_, pixel, radius, cv::Scalar(0), cv::FILLED);
      if (failed == CornerFailure::kStereoMatch) continue;
      Track t;
      t.uv0_px = corner.pt;
      t.disparity_px = *disparity;
      candidates.push_back(t);
    }
  }
  return candidates;
}

// One feature per track; the stereo ones carry their match.
std::vector<FrameFeature> KltFrontend::Features() {
  std::vector<FrameFeature> features;
  for (Track& t : tracks_) {
    FrameFeature f;
    f.id = t.id;
    f.tracked = t.tracked;
    f.uv0_px = Eigen::Vector2d(t.uv0_px.x, t.uv0_px.y);
    if (t.match) {
      f.uv1_px = t.match->uv1_px;
      f.z_px = t.match->z_px;
      f.stereo = true;
      t.disparity_px = f.z_px.x() - f.z_px.y();
    }
    features.push_back(f);
  }
  return features;
}

}  // namespace vio::frontend
