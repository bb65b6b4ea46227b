#include "vio/frontend/klt_frontend.h"

#include <algorithm>
#include <unordered_set>

#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

namespace vio::frontend {
namespace {

bool Inside(const cv::Point2f& p, const cv::Mat& image) {
  return p.x >= 0 && p.y >= 0 && p.x <= static_cast<float>(image.cols - 1) &&
         p.y <= static_cast<float>(image.rows - 1);
}

/// Depth whose disparity seeds new features before any feature has one [m].
constexpr double kDefaultDepthM = 5.0;

/// Features unmatched left-right for more consecutive frames are dropped.
constexpr int kMaxFramesWithoutStereo = 3;

double Median(std::vector<double> values, double fallback) {
  if (values.empty()) return fallback;
  const auto mid = values.begin() + static_cast<long>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

}  // namespace

KltFrontend::KltFrontend(const FrontendOptions& options, const StereoRectifier& rectifier)
    : StereoFrontend(options, rectifier),
      grid_(rectifier.camera_model(0).width(), rectifier.camera_model(0).height(), options.grid_cell_px) {}

std::vector<FrameFeature> KltFrontend::TrackFrame(const cv::Mat& left, const cv::Mat& right,
                                                  const FramePrior& prior) {
  std::int64_t start = NowNs();
  const std::vector<cv::Mat> left_pyramid = Pyramid(left);
  TrackTemporal(left_pyramid);
  AddTime(&StageTimes::temporal_ms, start);
  start = NowNs();
  DetectNew(left);
  AddTime(&StageTimes::detect_ms, start);
  start = NowNs();
  std::vector<FrameFeature> features = MatchStereo(left_pyramid, Pyramid(right));
  AddTime(&StageTimes::stereo_ms, start);
  const std::vector<LandmarkId> rejected = RejectOutliers(prior, &features);
  std::unordered_set<std::int64_t> dropped;
  for (LandmarkId id : rejected) dropped.insert(id.value);
  tracks_.erase(std::remove_if(tracks_.begin(), tracks_.end(),
                               [&](const Track& t) { return dropped.count(t.id.value) > 0; }),
                tracks_.end());
  previous_left_ = left_pyramid;
  return features;
}

std::vector<cv::Mat> KltFrontend::Pyramid(const cv::Mat& image) const {
  std::vector<cv::Mat> pyramid;
  const int side = options().klt_window_px;
  cv::buildOpticalFlowPyramid(image, pyramid, cv::Size(side, side), options().klt_pyramid_levels);
  return pyramid;
}

std::vector<bool> KltFrontend::TrackPoints(const std::vector<cv::Mat>& from, const std::vector<cv::Mat>& to,
                                           const std::vector<cv::Point2f>& points,
                                           std::vector<cv::Point2f>* guess) const {
  std::vector<bool> kept(points.size(), false);
  if (points.empty()) return kept;
  const cv::Size window(options().klt_window_px, options().klt_window_px);
  const int levels = options().klt_pyramid_levels;
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.01);
  std::vector<uchar> status, back_status;
  std::vector<float> error;
  cv::calcOpticalFlowPyrLK(from, to, points, *guess, status, error, window, levels, criteria,
                           cv::OPTFLOW_USE_INITIAL_FLOW);
  std::vector<cv::Point2f> back = points;
  cv::calcOpticalFlowPyrLK(to, from, *guess, back, back_status, error, window, levels, criteria,
                           cv::OPTFLOW_USE_INITIAL_FLOW);
  const double max_fb = options().klt_max_fb_px;
  for (size_t i = 0; i < points.size(); ++i) {
    kept[i] = status[i] && back_status[i] && Inside((*guess)[i], to[0]) && cv::norm(back[i] - points[i]) <= max_fb;
  }
  return kept;
}

void KltFrontend::TrackTemporal(const std::vector<cv::Mat>& left) {
  for (Track& t : tracks_) t.tracked = false;
  if (previous_left_.empty() || tracks_.empty()) return;
  std::vector<cv::Point2f> points, moved;
  for (const Track& t : tracks_) points.push_back(t.uv0_px);
  moved = points;
  const std::vector<bool> kept = TrackPoints(previous_left_, left, points, &moved);
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

cv::Mat KltFrontend::Thin(const cv::Mat& left, std::vector<int>* per_cell) {
  std::stable_sort(tracks_.begin(), tracks_.end(), [](const Track& a, const Track& b) { return a.age > b.age; });
  per_cell->assign(static_cast<size_t>(grid_.num_cells()), 0);
  cv::Mat mask(left.size(), CV_8UC1, cv::Scalar(255));
  const int radius = static_cast<int>(options().klt_min_distance_px);
  std::vector<Track> kept;
  for (const Track& t : tracks_) {
    int& n = (*per_cell)[static_cast<size_t>(grid_.Cell(t.uv0_px))];
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
  return mask;
}

// New FAST corners, strongest first, at least klt_min_distance_px from every
// feature, into the cells holding fewer than klt_per_cell.
void KltFrontend::DetectNew(const cv::Mat& left) {
  std::vector<int> count;
  cv::Mat mask = Thin(left, &count);
  const int per_cell = options().klt_per_cell;
  if (std::none_of(count.begin(), count.end(), [&](int n) { return n < per_cell; })) return;
  std::vector<cv::KeyPoint> corners;
  cv::FAST(left, corners, options().klt_fast_threshold, /*nonmaxSuppression=*/true);
  std::stable_sort(corners.begin(), corners.end(),
                   [](const cv::KeyPoint& a, const cv::KeyPoint& b) { return a.response > b.response; });
  const int radius = static_cast<int>(options().klt_min_distance_px);
  for (const cv::KeyPoint& c : corners) {
    int& n = count[static_cast<size_t>(grid_.Cell(c.pt))];
    const cv::Point pixel(cvRound(c.pt.x), cvRound(c.pt.y));
    if (n >= per_cell || mask.at<uchar>(pixel) == 0) continue;
    ++n;
    cv::circle(mask, pixel, radius, cv::Scalar(0), cv::FILLED);
    Track t;
    t.id = NewTrack();
    t.uv0_px = c.pt;
    tracks_.push_back(t);
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

// Left -> right LK from the previous disparity (else the median one), then
// the epipolar check.
std::vector<FrameFeature> KltFrontend::MatchStereo(const std::vector<cv::Mat>& left,
                                                   const std::vector<cv::Mat>& right) {
  std::vector<double> known;
  for (const Track& t : tracks_) {
    if (t.has_disparity) known.push_back(t.disparity_px);
  }
  const RectifiedStereo& stereo = rectifier().rectified();
  const double fallback = Median(known, stereo.f * stereo.baseline / kDefaultDepthM);
  std::vector<cv::Point2f> points, matched;
  for (const Track& t : tracks_) {
    points.push_back(t.uv0_px);
    matched.push_back(RightPixelAt(t.uv0_px, t.has_disparity ? t.disparity_px : fallback));
  }
  const std::vector<bool> kept = TrackPoints(left, right, points, &matched);
  std::vector<FrameFeature> features;
  for (size_t i = 0; i < tracks_.size(); ++i) {
    Track& t = tracks_[i];
    FrameFeature f;
    f.id = t.id;
    f.tracked = t.tracked;
    f.uv0_px = Eigen::Vector2d(t.uv0_px.x, t.uv0_px.y);
    const std::optional<Eigen::Vector3d> z =
        kept[i] ? StereoMeasurement(f.uv0_px, Eigen::Vector2d(matched[i].x, matched[i].y)) : std::nullopt;
    if (z) {
      f.uv1_px = Eigen::Vector2d(matched[i].x, matched[i].y);
      f.z_px = *z;
      f.stereo = true;
      t.disparity_px = z->x() - z->y();
      t.has_disparity = true;
      t.frames_without_stereo = 0;
    } else {
      ++t.frames_without_stereo;
    }
    features.push_back(f);
  }
  return features;
}

}  // namespace vio::frontend
