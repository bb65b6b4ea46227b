#include "vio/simulator/scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace vio::tools {
namespace {

constexpr double kWallGap = 0.05;  // boxes keep this far from walls and each other [m]
constexpr int kMaxPathSamples = 4000;

// Slab test: the parameter interval where origin + t * direction lies inside
// `box`, and the face it enters through. False when the line misses the box.
bool IntersectBox(const Eigen::AlignedBox3d& box, const Eigen::Vector3d& origin,
                  const Eigen::Vector3d& direction, double* t_enter, double* t_exit,
                  int* enter_face) {
  double t_near = -std::numeric_limits<double>::infinity();
  double t_far = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (direction[a] == 0.0) {
      if (origin[a] < box.min()[a] || origin[a] > box.max()[a]) return false;
      continue;
    }
    const double t_min_face = (box.min()[a] - origin[a]) / direction[a];
    const double t_max_face = (box.max()[a] - origin[a]) / direction[a];
    const bool positive = direction[a] > 0.0;
    const double t_in = positive ? t_min_face : t_max_face;
    const double t_out = positive ? t_max_face : t_min_face;
    if (t_in > t_near) {
      t_near = t_in;
      *enter_face = 2 * a + (positive ? 0 : 1);
    }
    t_far = std::min(t_far, t_out);
  }
  *t_enter = t_near;
  *t_exit = t_far;
  return t_near <= t_far;
}

double DistanceToBox(const Eigen::AlignedBox3d& box, const Eigen::Vector3d& p) {
  const Eigen::Vector3d outside =
      (box.min() - p).cwiseMax(p - box.max()).cwiseMax(Eigen::Vector3d::Zero());
  return outside.norm();
}

void CheckOptions(const SceneOptions& options) {
  if (!(options.room_size_m.minCoeff() > 0.0)) {
    throw std::invalid_argument("scene: room size must be positive in x, y and z");
  }
  if (!(options.trajectory_margin_m >= 0.0)) {
    throw std::invalid_argument("scene: the room margin around the trajectory must be >= 0, got " +
                                std::to_string(options.trajectory_margin_m) + " m");
  }
  if (!(options.landmark_density_per_m2 > 0.0)) {
    throw std::invalid_argument("scene: landmark density must be positive, got " +
                                std::to_string(options.landmark_density_per_m2));
  }
  if (options.num_boxes < 0 || !(options.box_min_size_m > 0.0) ||
      options.box_max_size_m < options.box_min_size_m) {
    throw std::invalid_argument("scene: need num_boxes >= 0 and 0 < box_min_size <= box_max_size");
  }
}

Eigen::AlignedBox3d FitRoom(const SceneOptions& options, const std::vector<Eigen::Vector3d>& path_w) {
  Eigen::AlignedBox3d room(options.room_center_m - 0.5 * options.room_size_m,
                           options.room_center_m + 0.5 * options.room_size_m);
  const Eigen::Vector3d margin = Eigen::Vector3d::Constant(options.trajectory_margin_m);
  for (const Eigen::Vector3d& p : path_w) {
    room.extend(p - margin);
    room.extend(p + margin);
  }
  return room;
}

// Every `stride`-th path point, so box placement stays cheap on long paths.
std::vector<Eigen::Vector3d> Subsample(const std::vector<Eigen::Vector3d>& path_w) {
  const std::size_t stride = std::max<std::size_t>(1, path_w.size() / kMaxPathSamples);
  std::vector<Eigen::Vector3d> out;
  for (std::size_t i = 0; i < path_w.size(); i += stride) out.push_back(path_w[i]);
  return out;
}

bool BoxFits(const Eigen::AlignedBox3d& box, const std::vector<Eigen::AlignedBox3d>& boxes,
             const std::vector<Eigen::Vector3d>& path_w, double clearance_m) {
  for (const Eigen::AlignedBox3d& other : boxes) {
    const Eigen::Vector3d gap = Eigen::Vector3d::Constant(kWallGap);
    if (Eigen::AlignedBox3d(other.min() - gap, other.max() + gap).intersects(box)) return false;
  }
  for (const Eigen::Vector3d& p : path_w) {
    if (DistanceToBox(box, p) < clearance_m) return false;
  }
  return true;
}

std::vector<Eigen::AlignedBox3d> PlaceBoxes(const SceneOptions& options, const Eigen::AlignedBox3d& room,
                                            const std::vector<Eigen::Vector3d>& path_w,
                                            std::mt19937_64* rng) {
  const std::vector<Eigen::Vector3d> samples = Subsample(path_w);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Eigen::AlignedBox3d> boxes;
  const double max_height = std::max(options.box_min_size_m, room.sizes().z() - 0.5);
  for (int attempt = 0; attempt < 200 * options.num_boxes &&
                        static_cast<int>(boxes.size()) < options.num_boxes;
       ++attempt) {
    const double span = options.box_max_size_m - options.box_min_size_m;
    const Eigen::Vector3d size(options.box_min_size_m + span * unit(*rng),
                               options.box_min_size_m + span * unit(*rng),
                               std::min(max_height, options.box_min_size_m + span * unit(*rng)));
    const Eigen::Vector3d free = room.sizes() - size - Eigen::Vector3d::Constant(2.0 * kWallGap);
    if (free.x() <= 0.0 || free.y() <= 0.0) continue;
    Eigen::Vector3d min_corner(room.min().x() + kWallGap + free.x() * unit(*rng),
                               room.min().y() + kWallGap + free.y() * unit(*rng), room.min().z());
    const Eigen::AlignedBox3d box(min_corner, min_corner + size);
    if (BoxFits(box, boxes, samples, options.box_clearance_m)) boxes.push_back(box);
  }
  return boxes;
}

bool InsideOtherBox(const Eigen::Vector3d& p, int own_box, const std::vector<Eigen::AlignedBox3d>& boxes) {
  for (std::size_t b = 0; b < boxes.size(); ++b) {
    if (static_cast<int>(b) == own_box) continue;
    const Eigen::Vector3d eps = Eigen::Vector3d::Constant(1e-9);
    if (Eigen::AlignedBox3d(boxes[b].min() - eps, boxes[b].max() + eps).contains(p)) return true;
  }
  return false;
}

// Stratified samples on face (axis, side) of `box`: one uniform point per
// cell of a grid whose cell area is 1 / density.
void SampleFace(const Eigen::AlignedBox3d& box, int axis, int side, const Eigen::Vector3d& normal_w,
                int box_index, const SceneOptions& options, std::mt19937_64* rng,
                std::vector<SceneLandmark>* landmarks) {
  const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
  const double size1 = box.sizes()[a1], size2 = box.sizes()[a2];
  const double cell = 1.0 / std::sqrt(options.landmark_density_per_m2);
  const int n1 = std::max(1, static_cast<int>(std::lround(size1 / cell)));
  const int n2 = std::max(1, static_cast<int>(std::lround(size2 / cell)));
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < n1; ++i) {
    for (int j = 0; j < n2; ++j) {
      SceneLandmark landmark;
      landmark.p_w[axis] = side == 0 ? box.min()[axis] : box.max()[axis];
      landmark.p_w[a1] = box.min()[a1] + size1 * (i + unit(*rng)) / n1;
      landmark.p_w[a2] = box.min()[a2] + size2 * (j + unit(*rng)) / n2;
      landmark.normal_w = normal_w;
      landmark.box = box_index;
      landmarks->push_back(landmark);
    }
  }
}

std::vector<SceneLandmark> SampleLandmarks(const Scene& scene, const SceneOptions& options,
                                           std::mt19937_64* rng) {
  std::vector<SceneLandmark> all;
  for (int face = 0; face < 6; ++face) {
    const int axis = face / 2, side = face % 2;
    const Eigen::Vector3d inward = (side == 0 ? 1.0 : -1.0) * Eigen::Vector3d::Unit(axis);
    SampleFace(scene.room, axis, side, inward, -1, options, rng, &all);
  }
  for (std::size_t b = 0; b < scene.boxes.size(); ++b) {
    for (int face = 0; face < 6; ++face) {
      if (face == 4) continue;  // the bottom stands on the floor
      const int axis = face / 2, side = face % 2;
      const Eigen::Vector3d outward = (side == 0 ? -1.0 : 1.0) * Eigen::Vector3d::Unit(axis);
      SampleFace(scene.boxes[b], axis, side, outward, static_cast<int>(b), options, rng, &all);
    }
  }
  std::vector<SceneLandmark> visible;
  for (const SceneLandmark& landmark : all) {
    if (!InsideOtherBox(landmark.p_w, landmark.box, scene.boxes)) visible.push_back(landmark);
  }
  return visible;
}

}  // namespace

bool Scene::SegmentBlocked(const Eigen::Vector3d& from, const Eigen::Vector3d& to, int skip_box) const {
  const Eigen::Vector3d direction = to - from;
  for (std::size_t b = 0; b < boxes.size(); ++b) {
    if (static_cast<int>(b) == skip_box) continue;
    double t_enter = 0.0, t_exit = 0.0;
    int face = 0;
    if (IntersectBox(boxes[b], from, direction, &t_enter, &t_exit, &face) && t_enter < 1.0 - 1e-9 &&
        t_exit > 1e-9) {
      return true;
    }
  }
  return false;
}

Scene::RayHit Scene::CastRay(const Eigen::Vector3d& origin_w, const Eigen::Vector3d& direction_w) const {
  RayHit hit;
  if (!room.contains(origin_w)) return hit;
  hit.t = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {  // leaving the convex room through one face
    if (direction_w[a] == 0.0) continue;
    const bool positive = direction_w[a] > 0.0;
    const double t = ((positive ? room.max()[a] : room.min()[a]) - origin_w[a]) / direction_w[a];
    if (t < hit.t) hit = {t, 2 * a + (positive ? 1 : 0)};
  }
  for (std::size_t b = 0; b < boxes.size(); ++b) {
    double t_enter = 0.0, t_exit = 0.0;
    int face = 0;
    if (IntersectBox(boxes[b], origin_w, direction_w, &t_enter, &t_exit, &face) && t_enter > 0.0 &&
        t_enter < hit.t) {
      hit = {t_enter, 6 + 6 * static_cast<int>(b) + face};
    }
  }
  return hit;
}

Scene BuildScene(const SceneOptions& options, const std::vector<Eigen::Vector3d>& path_w,
                 std::mt19937_64* rng) {
  CheckOptions(options);
  Scene scene;
  scene.room = FitRoom(options, path_w);
  scene.boxes = PlaceBoxes(options, scene.room, path_w, rng);
  scene.landmarks = SampleLandmarks(scene, options, rng);
  return scene;
}

}  // namespace vio::tools
