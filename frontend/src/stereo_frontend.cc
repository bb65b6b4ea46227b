#include "vio/frontend/stereo_frontend.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include <glog/logging.h>

#include "vio/estimator/stereo_geometry.h"
#include "vio/frontend/brisk_frontend.h"
#include "vio/frontend/klt_frontend.h"

namespace vio::frontend {
namespace {

constexpr double kRowHistogramBinPx = 0.01;
/// Smallest disparity a track's own triangulation is made from [px].
constexpr double kMinTriangulationDisparityPx = 1.0;

void Require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("front end options: " + what);
}

void CheckOptions(const FrontendOptions& o) {
  Require(o.max_epipolar_px > 0, "max_epipolar_px must be > 0");
  Require(o.grid_cell_px >= 4, "grid_cell_px must be >= 4");
  Require(o.max_reprojection_px > 0, "max_reprojection_px must be > 0");
  Require(o.brisk_threshold > 0, "brisk_threshold must be > 0");
  Require(o.brisk_octaves >= 0, "brisk_octaves must be >= 0");
  Require(o.brisk_per_cell > 0, "brisk_per_cell must be > 0");
  Require(o.brisk_max_disparity_px > 0, "brisk_max_disparity_px must be > 0");
  Require(o.max_hamming_bits > 0 && o.max_hamming_bits <= 512, "max_hamming_bits must be in (0, 512]");
  Require(o.track_window_frames >= 1, "track_window_frames must be >= 1");
  Require(o.reidentify_radius_px >= 0, "reidentify_radius_px must be >= 0");
  Require(o.klt_per_cell > 0, "klt_per_cell must be > 0");
  Require(o.klt_fast_threshold > 0, "klt_fast_threshold must be > 0");
  Require(o.klt_min_distance_px >= 0, "klt_min_distance_px must be >= 0");
  Require(o.klt_window_px >= 5, "klt_window_px must be >= 5");
  Require(o.klt_pyramid_levels >= 0, "klt_pyramid_levels must be >= 0");
  Require(o.klt_max_fb_px > 0, "klt_max_fb_px must be > 0");
}

void CheckImage(const cv::Mat& image, const CameraCalibration& camera, const char* which) {
  if (image.type() != CV_8UC1 || image.cols != camera.width || image.rows != camera.height) {
    throw std::invalid_argument(std::string("StereoFrontend: the ") + which + " image must be 8-bit grey " +
                                std::to_string(camera.width) + "x" + std::to_string(camera.height) + ", got " +
                                std::to_string(image.cols) + "x" + std::to_string(image.rows) + " of type " +
                                std::to_string(image.type()));
  }
}

}  // namespace

double FrontendStats::MedianRowDifferencePx() const {
  std::int64_t total = 0;
  for (std::int64_t n : row_difference_histogram) total += n;
  if (total == 0) return 0.0;
  std::int64_t seen = 0;
  for (size_t i = 0; i < row_difference_histogram.size(); ++i) {
    seen += row_difference_histogram[i];
    if (2 * seen >= total) return (static_cast<double>(i) + 0.5) * kRowHistogramBinPx;
  }
  return static_cast<double>(row_difference_histogram.size()) * kRowHistogramBinPx;
}

StereoFrontend::StereoFrontend(const FrontendOptions& options, const StereoRectifier& rectifier)
    : options_(options), rectifier_(rectifier) {
  CheckOptions(options_);
  stats_.row_difference_histogram.assign(
      static_cast<size_t>(std::ceil(options_.max_epipolar_px / kRowHistogramBinPx)) + 1, 0);
}

StereoFrame StereoFrontend::Process(Timestamp t_ns, const cv::Mat& left, const cv::Mat& right,
                                    const FramePrior& prior) {
  const std::int64_t start = NowNs();
  Prepare(left, right, /*with_corners=*/false, &scratch_);
  const double prepare_ms = 1e-6 * static_cast<double>(NowNs() - start);
  StereoFrame frame = Process(t_ns, &scratch_, prior);
  AddPrepareTime(prepare_ms);
  return frame;
}

void StereoFrontend::AddPrepareTime(double ms) {
  last_times_.prepare_ms += ms;
  stats_.time.prepare_ms += ms;
}

void StereoFrontend::Prepare(const cv::Mat& left, const cv::Mat& right, bool with_corners,
                             PreparedPair* pair) const {
  CheckImage(left, rectifier_.camera_model(0).calibration(), "left");
  CheckImage(right, rectifier_.camera_model(1).calibration(), "right");
  pair->left = left;
  pair->right = right;
  pair->corners.clear();
  pair->corners_ready = false;
  PrepareImages(with_corners, pair);
}

StereoFrame StereoFrontend::Process(Timestamp t_ns, PreparedPair* pair, const FramePrior& prior) {
  last_times_ = StageTimes{};
  features_ = TrackFrame(pair, prior);
  StereoFrame frame = Emit(t_ns, prior);
  ++stats_.frames;
  stats_.observations_per_frame.push_back(static_cast<int>(frame.observations.size()));
  stats_.time.detect_ms += last_times_.detect_ms;
  stats_.time.stereo_ms += last_times_.stereo_ms;
  stats_.time.temporal_ms += last_times_.temporal_ms;
  stats_.time.reject_ms += last_times_.reject_ms;
  return frame;
}

// The stereo features become observations; each is recorded in the two-way
// index and, with a predicted pose, triangulated into the world.
StereoFrame StereoFrontend::Emit(Timestamp t_ns, const FramePrior& prior) {
  StereoFrame frame;
  frame.t_ns = t_ns;
  const RectifiedStereo& stereo = rectifier_.rectified();
  std::optional<Eigen::Isometry3d> T_w_cl;
  if (prior.T_w_b) T_w_cl = *prior.T_w_b * stereo.T_b_cl;
  for (const FrameFeature& f : features_) {
    if (!f.stereo) continue;
    frame.observations.push_back(StereoObservation{f.id, f.z_px});
    tracks_.Observe(f.id, stats_.frames);
    if (!T_w_cl) continue;
    const std::optional<Eigen::Vector3d> p_cl = TriangulateRectified(f.z_px, stereo, kMinTriangulationDisparityPx);
    if (p_cl) tracks_.SetPosition(f.id, *T_w_cl * *p_cl);
  }
  return frame;
}

std::optional<Eigen::Vector3d> StereoFrontend::StereoMeasurement(const Eigen::Vector2d& uv0_px,
                                                                 const Eigen::Vector2d& uv1_px) {
  ++stats_.stereo_candidates;
  const std::optional<Eigen::Vector2d> left = rectifier_.Rectify(0, uv0_px);
  const std::optional<Eigen::Vector2d> right = rectifier_.Rectify(1, uv1_px);
  if (!left || !right) return std::nullopt;
  const double row_difference = std::abs(left->y() - right->y());
  if (row_difference > options_.max_epipolar_px || left->x() - right->x() <= 0.0) return std::nullopt;
  ++stats_.stereo_inliers;
  std::vector<std::int64_t>& histogram = stats_.row_difference_histogram;
  const auto bin = static_cast<size_t>(row_difference / kRowHistogramBinPx);
  ++histogram[std::min(bin, histogram.size() - 1)];
  return Eigen::Vector3d(left->x(), right->x(), 0.5 * (left->y() + right->y()));
}

std::optional<Eigen::Vector3d> StereoFrontend::LandmarkPosition(LandmarkId id, const FramePrior& prior) const {
  if (prior.landmarks != nullptr) {
    const auto it = prior.landmarks->find(id);
    if (it != prior.landmarks->end()) return it->second.position();
  }
  return tracks_.Position(id);
}

// A tracked feature is an outlier when its landmark, seen from the predicted
// camera, projects more than max_reprojection_px away from the measurement
// (in u_L, v and, for stereo features, u_R) or lies behind the camera.
std::vector<LandmarkId> StereoFrontend::RejectOutliers(const FramePrior& prior, std::vector<FrameFeature>* features) {
  const std::int64_t start = NowNs();
  std::vector<LandmarkId> rejected;
  const RectifiedStereo& stereo = rectifier_.rectified();
  std::optional<Eigen::Isometry3d> T_cl_w;
  if (prior.T_w_b) T_cl_w = (*prior.T_w_b * stereo.T_b_cl).inverse();
  auto outlier = [&](const FrameFeature& f) {
    if (!f.tracked) return false;
    ++stats_.temporal_matches;
    const std::optional<Eigen::Vector3d> p_w = T_cl_w ? LandmarkPosition(f.id, prior) : std::nullopt;
    if (!p_w) return false;
    const Eigen::Vector3d p_cl = *T_cl_w * *p_w;
    bool bad = p_cl.z() <= 0.0;
    if (!bad) {
      const Eigen::Vector3d z_pred = ProjectRectified(p_cl, stereo);
      const std::optional<Eigen::Vector2d> left = rectifier_.Rectify(0, f.uv0_px);
      const double du_r = f.stereo ? std::abs(z_pred.y() - f.z_px.y()) : 0.0;
      bad = !left || std::max({std::abs(z_pred.x() - left->x()), std::abs(z_pred.z() - left->y()), du_r}) >
                         options_.max_reprojection_px;
    }
    if (bad) rejected.push_back(f.id);
    return bad;
  };
  features->erase(std::remove_if(features->begin(), features->end(), outlier), features->end());
  stats_.rejected_reprojection += static_cast<std::int64_t>(rejected.size());
  AddTime(&StageTimes::reject_ms, start);
  return rejected;
}

LandmarkId StereoFrontend::NewTrack() {
  ++stats_.new_tracks;
  return tracks_.NewTrack();
}

void StereoFrontend::AddTime(double StageTimes::*stage, std::int64_t start_ns) {
  last_times_.*stage += 1e-6 * static_cast<double>(NowNs() - start_ns);
}

std::int64_t StereoFrontend::NowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

std::unique_ptr<StereoFrontend> MakeStereoFrontend(const FrontendOptions& options, const StereoRectifier& rectifier) {
  if (options.frontend == "brisk") return std::make_unique<BriskFrontend>(options, rectifier);
  if (options.frontend == "klt") return std::make_unique<KltFrontend>(options, rectifier);
  throw std::invalid_argument("MakeStereoFrontend: '" + options.frontend + "' is not an image front end (brisk, klt)");
}

}  // namespace vio::frontend
