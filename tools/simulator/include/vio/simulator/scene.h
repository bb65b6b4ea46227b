#pragma once
// The simulator's world: an axis-aligned room (walls, floor, ceiling) with
// axis-aligned clutter boxes standing on the floor, and 3D landmarks sampled
// on every visible surface.
//
// Surfaces are numbered for texturing: face f = 2 * axis + side (side 0 = the
// min face, 1 = the max face) of the room is surface f; face f of box b is
// surface 6 + 6 b + f.
#include <cstdint>
#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace vio::tools {

struct SceneOptions {
  /// Room extent along world x, y, z [m] (EuRoC Vicon room: about 8 x 8 x 4).
  Eigen::Vector3d room_size_m = Eigen::Vector3d(8.0, 8.0, 4.0);
  /// Room centre in world [m]: the EuRoC V1/V2 ground-truth trajectories
  /// (x in [-3.6, 2.1], y in [-1.9, 3.3], z in [0.9, 2.2]) lie well inside.
  Eigen::Vector3d room_center_m = Eigen::Vector3d(-0.75, 0.7, 2.0);
  /// The room grows (per side) until the trajectory keeps this distance to
  /// every wall, floor and ceiling [m].
  double trajectory_margin_m = 0.3;
  /// Number of clutter boxes on the floor (fewer when they do not fit).
  int num_boxes = 8;
  /// Smallest box edge [m].
  double box_min_size_m = 0.4;
  /// Largest box edge [m] (heights also stay 0.5 m below the ceiling).
  double box_max_size_m = 1.5;
  /// Minimum distance between a box and the trajectory [m].
  double box_clearance_m = 0.6;
  /// Landmarks per square metre of surface [1/m^2].
  double landmark_density_per_m2 = 10.0;
};

/// One 3D point on a surface.
struct SceneLandmark {
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();       ///< [m]
  Eigen::Vector3d normal_w = Eigen::Vector3d::UnitZ();  ///< unit, pointing into free space
  int box = -1;                                         ///< box it lies on, -1 for the room
};

struct Scene {
  Eigen::AlignedBox3d room;                ///< inner extent of the room [m]
  std::vector<Eigen::AlignedBox3d> boxes;  ///< clutter, inside the room [m]
  std::vector<SceneLandmark> landmarks;

  /// True when the segment from `from` to `to` passes through a box other
  /// than `skip_box` (the room is convex, so its walls never occlude).
  bool SegmentBlocked(const Eigen::Vector3d& from, const Eigen::Vector3d& to, int skip_box) const;

  /// The first surface a ray from inside the room hits: its distance along
  /// the unit direction and its number (surface -1 when nothing is hit, i.e.
  /// the origin is outside the room).
  struct RayHit {
    double t = 0.0;    ///< [m]
    int surface = -1;  ///< see the numbering above
  };
  RayHit CastRay(const Eigen::Vector3d& origin_w, const Eigen::Vector3d& direction_w) const;
};

/// The room from `options`, grown to keep `path_w` inside by the margin;
/// boxes placed at random (rejecting those closer than the clearance to
/// `path_w` or overlapping another box); landmarks on every face that can be
/// seen (no box bottoms, no floor under a box), stratified (one uniform point
/// per cell of a grid with the requested density). Throws
/// std::invalid_argument on non-positive sizes or density.
Scene BuildScene(const SceneOptions& options, const std::vector<Eigen::Vector3d>& path_w,
                 std::mt19937_64* rng);

}  // namespace vio::tools
