#include "vio/dataset/stereo_frames.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

namespace vio::tools {
namespace {

struct PixelPair {
  std::optional<Eigen::Vector2d> uv[2];
};

// True when the pair passes the epipolar and disparity tests with the cameras exchanged.
bool ConsistentIfSwapped(const PixelPair& pair, const frontend::StereoRectifier& rectifier, double max_epipolar_px) {
  const std::optional<Eigen::Vector2d> left = rectifier.Rectify(0, *pair.uv[1]);
  const std::optional<Eigen::Vector2d> right = rectifier.Rectify(1, *pair.uv[0]);
  return left && right && std::abs(left->y() - right->y()) <= max_epipolar_px && left->x() - right->x() > 0;
}

// One frame's rows (feature id -> pixels in cam0 / cam1, in id order) to measurements.
template <typename Rows>
void AddStereoObservations(const Rows& rows,
                           const frontend::StereoRectifier& rectifier, double max_epipolar_px, StereoFrame* frame,
                           StereoFramesReport* report) {
  frame->observations.reserve(frame->observations.size() + rows.size());
  for (const auto& [id, pair] : rows) {
    if (!pair.uv[1]) { ++report->left_only; continue; }
    if (!pair.uv[0]) { ++report->right_only; continue; }
    if (!rectifier.camera_model(0).InImage(*pair.uv[0]) || !rectifier.camera_model(1).InImage(*pair.uv[1])) {
      ++report->rejected_outside_image;
      continue;
    }
    const std::optional<Eigen::Vector2d> left = rectifier.Rectify(0, *pair.uv[0]);
    const std::optional<Eigen::Vector2d> right = rectifier.Rectify(1, *pair.uv[1]);
    if (!left || !right) { ++report->unrectifiable; continue; }
    const bool epipolar = std::abs(left->y() - right->y()) <= max_epipolar_px;
    if (!epipolar || left->x() - right->x() <= 0) {
      ++(epipolar ? report->rejected_disparity : report->rejected_epipolar);
      report->consistent_if_swapped += ConsistentIfSwapped(pair, rectifier, max_epipolar_px);
      continue;
    }
    StereoObservation obs;
    obs.landmark = LandmarkId(id);
    obs.z_px = Eigen::Vector3d(left->x(), right->x(), 0.5 * (left->y() + right->y()));
    frame->observations.push_back(obs);
    ++report->stereo_observations;
  }
}

// The rows of one frame's features by feature id, in id order, as a map of them would hold them
// (a later row of an id and camera replaces an earlier one), without a node per row.
std::vector<std::pair<std::int64_t, PixelPair>> RowsById(const std::vector<FeatureObservation>& features) {
  std::vector<const FeatureObservation*> by_id;
  by_id.reserve(features.size());
  for (const FeatureObservation& obs : features) by_id.push_back(&obs);
  std::stable_sort(by_id.begin(), by_id.end(), [](const FeatureObservation* a, const FeatureObservation* b) {
    return a->feature_id < b->feature_id;
  });
  std::vector<std::pair<std::int64_t, PixelPair>> rows;
  rows.reserve(by_id.size());
  for (const FeatureObservation* obs : by_id) {
    if (rows.empty() || rows.back().first != obs->feature_id) rows.emplace_back(obs->feature_id, PixelPair{});
    rows.back().second.uv[obs->camera] = obs->uv_px;
  }
  return rows;
}

}  // namespace

StereoFrame StereoFrameFromFeatures(Timestamp t_ns, const std::vector<FeatureObservation>& features,
                                    const frontend::StereoRectifier& rectifier, double max_epipolar_px,
                                    StereoFramesReport* report) {
  StereoFrame frame;
  frame.t_ns = t_ns;
  AddStereoObservations(RowsById(features), rectifier, max_epipolar_px, &frame, report);
  return frame;
}

std::vector<StereoFrame> StereoFramesFromFeatures(const std::vector<FeatureObservation>& features,
                                                  const std::vector<CameraFrame>& cam0_frames,
                                                  const frontend::StereoRectifier& rectifier,
                                                  double max_epipolar_px, StereoFramesReport* report) {
  *report = StereoFramesReport{};
  std::map<Timestamp, std::map<std::int64_t, PixelPair>> by_time;
  for (const CameraFrame& f : cam0_frames) by_time[f.t_ns];
  for (const FeatureObservation& obs : features) {
    auto it = by_time.find(obs.t_ns);
    if (it == by_time.end()) { ++report->observations_off_frames; continue; }
    it->second[obs.feature_id].uv[obs.camera] = obs.uv_px;
  }
  std::vector<StereoFrame> frames;
  frames.reserve(by_time.size());
  for (const auto& [t_ns, rows] : by_time) {
    StereoFrame& frame = frames.emplace_back();
    frame.t_ns = t_ns;
    AddStereoObservations(rows, rectifier, max_epipolar_px, &frame, report);
  }
  report->frames = static_cast<int>(frames.size());
  return frames;
}

std::string SwappedCamerasProblem(const StereoFramesReport& report) {
  const int pairs = report.stereo_observations + report.rejected_epipolar + report.rejected_disparity;
  if (pairs < kSwappedMinPairs || 2 * report.consistent_if_swapped < pairs) return "";
  std::ostringstream why;
  why << report.consistent_if_swapped << " of " << pairs << " stereo pairs so far fit the stereo geometry only "
      << "with cam0 and cam1 exchanged (" << report.stereo_observations << " as given): are the cameras swapped? "
      << "cam0 must be the left camera: check the camera column of features0/data.csv against T_BS in cam0/cam1 "
      << "sensor.yaml";
  return why.str();
}

}  // namespace vio::tools
