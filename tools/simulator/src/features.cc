#include "vio/simulator/features.h"

#include <algorithm>
#include <optional>
#include <stdexcept>
#include <string>

#include "vio/frontend/camera_model.h"

namespace vio::tools {
namespace {

using frontend::CameraModel;

void CheckOptions(const FeatureSimOptions& options) {
  if (!(options.min_range_m >= 0.0) || !(options.max_range_m > options.min_range_m)) {
    throw std::invalid_argument("features: need 0 <= min_range < max_range, got " +
                                std::to_string(options.min_range_m) + " and " +
                                std::to_string(options.max_range_m) + " m");
  }
  if (options.max_features <= 0) {
    throw std::invalid_argument("features: max_features must be positive, got " +
                                std::to_string(options.max_features));
  }
  if (!(options.pixel_noise_px >= 0.0) || !(options.outlier_rate >= 0.0 && options.outlier_rate <= 1.0)) {
    throw std::invalid_argument("features: need pixel noise >= 0 and outlier rate in [0, 1]");
  }
  if (options.grid_cols <= 0 || options.grid_rows <= 0 || !(options.border_px >= 0.0)) {
    throw std::invalid_argument("features: need a positive grid and a border >= 0");
  }
}

// One camera at one frame: world-to-camera transform and camera centre.
struct CameraPose {
  Eigen::Matrix3d R_c_w;
  Eigen::Vector3d t_c_w;
  Eigen::Vector3d p_w_c;
};

class FeatureTracker {
 public:
  FeatureTracker(const Scene& scene, const std::array<CameraCalibration, 2>& cameras,
                 const FeatureSimOptions& options, std::mt19937_64* rng);

  /// Selects and observes the landmarks of one frame (appends to `out`).
  void ProcessFrame(int frame_index, const FramePose& frame, FeatureSimulation* out);
  /// Closes the tracks still running after the last frame.
  void Finish(FeatureSimulation* out);

 private:
  CameraPose PoseOf(int camera, const FramePose& frame) const;
  std::optional<Eigen::Vector2d> Observe(int camera, const CameraPose& pose, int landmark) const;
  void ObserveAllInCam0(const CameraPose& pose);
  bool VisibleInCam1(int landmark, const CameraPose& pose);
  std::vector<int> Select(const CameraPose& cam1_pose);
  int CellOf(const Eigen::Vector2d& uv) const;
  void UpdateTracks(const std::vector<int>& selected, FeatureSimulation* out);
  Eigen::Vector2d Corrupt(const Eigen::Vector2d& uv, const CameraModel& model);
  void Emit(Timestamp t_ns, const std::vector<int>& selected, FeatureSimulation* out);

  const Scene& scene_;
  std::array<CameraModel, 2> models_;
  std::array<Eigen::Isometry3d, 2> T_b_c_;
  FeatureSimOptions options_;
  std::mt19937_64* rng_;
  std::vector<double> strength_;         // fixed random corner strength per landmark
  std::vector<int> run_length_;          // frames in the current cam0 run, 0 when not tracked
  std::vector<int> tracked_;             // last frame's selection
  std::vector<char> visible0_;           // this frame, per landmark
  std::vector<Eigen::Vector2d> uv0_;     // this frame, valid where visible0_
  std::vector<int> cam1_stamp_;          // frame index cam1 was evaluated at, per landmark
  std::vector<std::optional<Eigen::Vector2d>> uv1_;
  int frame_index_ = -1;
};

FeatureTracker::FeatureTracker(const Scene& scene, const std::array<CameraCalibration, 2>& cameras,
                               const FeatureSimOptions& options, std::mt19937_64* rng)
    : scene_(scene),
      models_{CameraModel(cameras[0]), CameraModel(cameras[1])},
      T_b_c_{cameras[0].T_b_c, cameras[1].T_b_c},
      options_(options),
      rng_(rng) {
  const std::size_t n = scene.landmarks.size();
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  strength_.resize(n);
  for (double& s : strength_) s = unit(*rng_);
  run_length_.assign(n, 0);
  visible0_.assign(n, 0);
  uv0_.resize(n);
  cam1_stamp_.assign(n, -1);
  uv1_.resize(n);
}

CameraPose FeatureTracker::PoseOf(int camera, const FramePose& frame) const {
  const Eigen::Isometry3d T_w_c = frame.T_w_b * T_b_c_[camera];
  const Eigen::Isometry3d T_c_w = T_w_c.inverse();
  return {T_c_w.linear(), T_c_w.translation(), T_w_c.translation()};
}

std::optional<Eigen::Vector2d> FeatureTracker::Observe(int camera, const CameraPose& pose, int landmark) const {
  const SceneLandmark& l = scene_.landmarks[landmark];
  const Eigen::Vector3d p_c = pose.R_c_w * l.p_w + pose.t_c_w;
  const double range2 = p_c.squaredNorm();
  if (range2 < options_.min_range_m * options_.min_range_m ||
      range2 > options_.max_range_m * options_.max_range_m) {
    return std::nullopt;
  }
  if ((pose.p_w_c - l.p_w).dot(l.normal_w) <= 0.0) return std::nullopt;  // back of the surface
  const std::optional<Eigen::Vector2d> uv = models_[camera].ProjectUnbounded(p_c);
  if (!uv || !models_[camera].InImage(*uv, options_.border_px)) return std::nullopt;
  if (scene_.SegmentBlocked(pose.p_w_c, l.p_w, l.box)) return std::nullopt;
  return uv;
}

void FeatureTracker::ObserveAllInCam0(const CameraPose& pose) {
  for (std::size_t i = 0; i < scene_.landmarks.size(); ++i) {
    const std::optional<Eigen::Vector2d> uv = Observe(0, pose, static_cast<int>(i));
    visible0_[i] = uv.has_value();
    if (uv) uv0_[i] = *uv;
  }
}

bool FeatureTracker::VisibleInCam1(int landmark, const CameraPose& pose) {
  if (cam1_stamp_[landmark] != frame_index_) {
    uv1_[landmark] = Observe(1, pose, landmark);
    cam1_stamp_[landmark] = frame_index_;
  }
  return uv1_[landmark].has_value();
}

int FeatureTracker::CellOf(const Eigen::Vector2d& uv) const {
  const int col = std::clamp(static_cast<int>(uv.x() * options_.grid_cols / models_[0].width()), 0,
                             options_.grid_cols - 1);
  const int row = std::clamp(static_cast<int>(uv.y() * options_.grid_rows / models_[0].height()), 0,
                             options_.grid_rows - 1);
  return row * options_.grid_cols + col;
}

// Keep the still-visible tracks, then fill the budget cell by cell, always
// from the least occupied cell that still has candidates.
std::vector<int> FeatureTracker::Select(const CameraPose& cam1_pose) {
  const std::size_t budget = static_cast<std::size_t>(options_.max_features);
  std::vector<int> selected;
  std::vector<char> taken(scene_.landmarks.size(), 0);
  std::vector<int> occupancy(options_.grid_cols * options_.grid_rows, 0);
  for (int i : tracked_) {
    if (!visible0_[i] || selected.size() >= budget) continue;
    selected.push_back(i);
    taken[i] = 1;
    ++occupancy[CellOf(uv0_[i])];
  }
  std::vector<std::vector<int>> candidates(occupancy.size());
  for (std::size_t i = 0; i < visible0_.size(); ++i) {
    if (visible0_[i] && !taken[i]) candidates[CellOf(uv0_[i])].push_back(static_cast<int>(i));
  }
  for (std::vector<int>& cell : candidates) {  // best last, so pop_back takes it
    std::vector<std::pair<bool, int>> keyed;
    for (int i : cell) keyed.emplace_back(VisibleInCam1(i, cam1_pose), i);
    std::sort(keyed.begin(), keyed.end(), [this](const auto& a, const auto& b) {
      if (a.first != b.first) return !a.first;
      if (strength_[a.second] != strength_[b.second]) return strength_[a.second] < strength_[b.second];
      return a.second > b.second;
    });
    for (std::size_t k = 0; k < cell.size(); ++k) cell[k] = keyed[k].second;
  }
  while (selected.size() < budget) {
    int best = -1;
    for (std::size_t c = 0; c < candidates.size(); ++c) {
      if (!candidates[c].empty() && (best < 0 || occupancy[c] < occupancy[best])) best = static_cast<int>(c);
    }
    if (best < 0) break;
    selected.push_back(candidates[best].back());
    candidates[best].pop_back();
    ++occupancy[best];
  }
  return selected;
}

void FeatureTracker::UpdateTracks(const std::vector<int>& selected, FeatureSimulation* out) {
  std::vector<char> now(scene_.landmarks.size(), 0);
  for (int i : selected) now[i] = 1;
  for (int i : tracked_) {
    if (!now[i]) {
      out->track_lengths.push_back(run_length_[i]);
      run_length_[i] = 0;
    }
  }
  for (int i : selected) ++run_length_[i];
  tracked_ = selected;
}

Eigen::Vector2d FeatureTracker::Corrupt(const Eigen::Vector2d& uv, const CameraModel& model) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, options_.pixel_noise_px);
  const bool outlier = unit(*rng_) < options_.outlier_rate;
  const Eigen::Vector2d noise(normal(*rng_), normal(*rng_));
  if (outlier) return Eigen::Vector2d(unit(*rng_) * (model.width() - 1), unit(*rng_) * (model.height() - 1));
  // Clamping keeps the rare noisy pixel beyond the border inside the image.
  return (uv + noise)
      .cwiseMax(Eigen::Vector2d::Zero())
      .cwiseMin(Eigen::Vector2d(model.width() - 1, model.height() - 1));
}

void FeatureTracker::Emit(Timestamp t_ns, const std::vector<int>& selected, FeatureSimulation* out) {
  std::vector<int> ids = selected;
  std::sort(ids.begin(), ids.end());
  int stereo = 0;
  for (int camera : {0, 1}) {
    for (int i : ids) {
      if (camera == 1 && !uv1_[i]) continue;
      const Eigen::Vector2d& uv = camera == 0 ? uv0_[i] : *uv1_[i];
      out->observations.push_back({t_ns, camera, i, Corrupt(uv, models_[camera])});
      stereo += camera;
    }
  }
  out->cam0_count.push_back(static_cast<int>(ids.size()));
  out->stereo_count.push_back(stereo);
}

void FeatureTracker::ProcessFrame(int frame_index, const FramePose& frame, FeatureSimulation* out) {
  frame_index_ = frame_index;
  const CameraPose cam0 = PoseOf(0, frame), cam1 = PoseOf(1, frame);
  ObserveAllInCam0(cam0);
  const std::vector<int> selected = Select(cam1);
  for (int i : selected) VisibleInCam1(i, cam1);
  UpdateTracks(selected, out);
  Emit(frame.t_ns, selected, out);
}

void FeatureTracker::Finish(FeatureSimulation* out) { UpdateTracks({}, out); }

}  // namespace

FeatureSimulation SimulateFeatures(const Scene& scene, const std::array<CameraCalibration, 2>& cameras,
                                   const std::vector<FramePose>& frames, const FeatureSimOptions& options,
                                   std::mt19937_64* rng) {
  CheckOptions(options);
  FeatureTracker tracker(scene, cameras, options, rng);
  FeatureSimulation out;
  for (std::size_t k = 0; k < frames.size(); ++k) tracker.ProcessFrame(static_cast<int>(k), frames[k], &out);
  tracker.Finish(&out);
  return out;
}

double MedianTrackLength(const FeatureSimulation& features) {
  std::vector<int> lengths = features.track_lengths;
  if (lengths.empty()) return 0.0;
  const std::size_t mid = lengths.size() / 2;
  std::nth_element(lengths.begin(), lengths.begin() + mid, lengths.end());
  if (lengths.size() % 2 == 1) return lengths[mid];
  const int upper = lengths[mid];
  return 0.5 * (upper + *std::max_element(lengths.begin(), lengths.begin() + mid));
}

}  // namespace vio::tools
