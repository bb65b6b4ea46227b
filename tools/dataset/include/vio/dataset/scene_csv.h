#pragma once
// mav0/scene.csv of a dataset `vio simulate` made: the geometry of the world it
// rendered, so that what a front end matched can be checked against it
// (`vio matchcheck`). One row per axis-aligned box, world frame:
//   #kind,min_x [m],min_y [m],min_z [m],max_x [m],max_y [m],max_z [m]
// kind "room" (exactly once: the inner extent of the walls) or "box" (clutter).
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace vio::tools {

struct SceneBoxes {
  Eigen::AlignedBox3d room;                ///< inner extent of the room [m]
  std::vector<Eigen::AlignedBox3d> boxes;  ///< clutter [m]
};

/// Writes `path` (parent folders created); throws DatasetError when it cannot.
void WriteSceneCsv(const SceneBoxes& scene, const std::string& path);

/// Throws DatasetError "<path>:<line>: ..." on a malformed row, an unknown kind,
/// a box whose minimum is not below its maximum, a second room, and
/// "<path>: ..." when the file cannot be read or has no room.
SceneBoxes ReadSceneCsv(const std::string& path);

}  // namespace vio::tools
