// The simulator's room: fitting the trajectory, box placement, landmark
// sampling, occlusion and ray casting.
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "vio/simulator/scene.h"

namespace vio::tools {
namespace {

// A horizontal circle of radius 2 m at 1.5 m height around the default room centre.
std::vector<Eigen::Vector3d> CirclePath(const Eigen::Vector3d& center) {
  std::vector<Eigen::Vector3d> path;
  for (int i = 0; i < 400; ++i) {
    const double a = 2.0 * M_PI * i / 400;
    path.emplace_back(center.x() + 2.0 * std::cos(a), center.y() + 2.0 * std::sin(a), 1.5);
  }
  return path;
}

double SurfaceArea(const Scene& scene) {
  const Eigen::Vector3d r = scene.room.sizes();
  double area = 2.0 * (r.x() * r.y() + r.y() * r.z() + r.z() * r.x());
  for (const Eigen::AlignedBox3d& box : scene.boxes) {
    const Eigen::Vector3d s = box.sizes();
    area += s.x() * s.y() + 2.0 * (s.y() * s.z() + s.z() * s.x());  // no bottom
    area -= s.x() * s.y();                                           // floor under the box
  }
  return area;
}

TEST(BuildSceneTest, DefaultRoomKeepsBoxesAwayFromThePath) {
  const SceneOptions options;
  const std::vector<Eigen::Vector3d> path = CirclePath(options.room_center_m);
  std::mt19937_64 rng(1);
  const Scene scene = BuildScene(options, path, &rng);
  EXPECT_LT((scene.room.sizes() - options.room_size_m).norm(), 1e-12);  // the path fits
  EXPECT_EQ(static_cast<int>(scene.boxes.size()), options.num_boxes);
  for (std::size_t b = 0; b < scene.boxes.size(); ++b) {
    const Eigen::AlignedBox3d& box = scene.boxes[b];
    EXPECT_TRUE(scene.room.contains(box));
    EXPECT_DOUBLE_EQ(box.min().z(), scene.room.min().z());  // standing on the floor
    for (const Eigen::Vector3d& p : path) EXPECT_GE(box.exteriorDistance(p), options.box_clearance_m);
    for (std::size_t c = b + 1; c < scene.boxes.size(); ++c) EXPECT_FALSE(box.intersects(scene.boxes[c]));
  }
}

TEST(BuildSceneTest, RoomGrowsToEncloseThePathWithMargin) {
  SceneOptions options;
  options.room_size_m = Eigen::Vector3d(3.0, 3.0, 2.0);
  const std::vector<Eigen::Vector3d> path = CirclePath(options.room_center_m);
  std::mt19937_64 rng(1);
  const Scene scene = BuildScene(options, path, &rng);
  for (const Eigen::Vector3d& p : path) {
    EXPECT_GE(scene.room.exteriorDistance(p), 0.0);
    EXPECT_GE((p - scene.room.min()).minCoeff(), options.trajectory_margin_m - 1e-12);
    EXPECT_GE((scene.room.max() - p).minCoeff(), options.trajectory_margin_m - 1e-12);
  }
  EXPECT_NEAR(scene.room.sizes().x(), 4.0 + 2.0 * options.trajectory_margin_m, 1e-3);
}

TEST(BuildSceneTest, LandmarksHaveTheRequestedDensityOnFreeSurfaces) {
  SceneOptions options;
  options.landmark_density_per_m2 = 6.0;
  std::mt19937_64 rng(2);
  const Scene scene = BuildScene(options, CirclePath(options.room_center_m), &rng);
  const double expected = SurfaceArea(scene) * options.landmark_density_per_m2;
  EXPECT_NEAR(static_cast<double>(scene.landmarks.size()), expected, 0.1 * expected);
  for (const SceneLandmark& l : scene.landmarks) {
    EXPECT_NEAR(l.normal_w.norm(), 1.0, 1e-12);
    EXPECT_TRUE(scene.room.contains(l.p_w));
    const Eigen::Vector3d outside = l.p_w + 1e-3 * l.normal_w;  // a step into free space
    EXPECT_TRUE(scene.room.contains(outside));
    for (const Eigen::AlignedBox3d& box : scene.boxes) EXPECT_FALSE(box.contains(outside));
  }
}

TEST(BuildSceneTest, RejectsBadOptions) {
  std::mt19937_64 rng(1);
  SceneOptions options;
  options.landmark_density_per_m2 = 0.0;
  EXPECT_THROW(BuildScene(options, {}, &rng), std::invalid_argument);
  options = SceneOptions();
  options.room_size_m.z() = -1.0;
  EXPECT_THROW(BuildScene(options, {}, &rng), std::invalid_argument);
  options = SceneOptions();
  options.trajectory_margin_m = -0.1;
  EXPECT_THROW(BuildScene(options, {}, &rng), std::invalid_argument);
}

Scene OneBoxScene() {
  Scene scene;
  scene.room = Eigen::AlignedBox3d(Eigen::Vector3d(-4, -4, 0), Eigen::Vector3d(4, 4, 4));
  scene.boxes.emplace_back(Eigen::Vector3d(1, -0.5, 0), Eigen::Vector3d(2, 0.5, 1));
  return scene;
}

TEST(SceneTest, SegmentBlockedOnlyThroughOtherBoxes) {
  const Scene scene = OneBoxScene();
  const Eigen::Vector3d eye(0.0, 0.0, 0.5);
  EXPECT_TRUE(scene.SegmentBlocked(eye, Eigen::Vector3d(4.0, 0.0, 0.5), -1));   // wall behind the box
  EXPECT_FALSE(scene.SegmentBlocked(eye, Eigen::Vector3d(4.0, 3.0, 0.5), -1));  // beside it
  EXPECT_FALSE(scene.SegmentBlocked(eye, Eigen::Vector3d(1.0, 0.0, 0.5), 0));   // on its own face
  EXPECT_FALSE(scene.SegmentBlocked(eye, Eigen::Vector3d(0.9, 0.0, 0.5), -1));  // stops short
}

TEST(SceneTest, CastRayHitsTheNearestSurface) {
  const Scene scene = OneBoxScene();
  const Eigen::Vector3d eye(0.0, 0.0, 0.5);
  const Scene::RayHit box = scene.CastRay(eye, Eigen::Vector3d::UnitX());
  EXPECT_NEAR(box.t, 1.0, 1e-12);
  EXPECT_EQ(box.surface, 6 + 0);  // box 0, face x-min
  const Scene::RayHit wall = scene.CastRay(eye, -Eigen::Vector3d::UnitX());
  EXPECT_NEAR(wall.t, 4.0, 1e-12);
  EXPECT_EQ(wall.surface, 0);  // room face x-min
  const Scene::RayHit ceiling = scene.CastRay(eye, Eigen::Vector3d::UnitZ());
  EXPECT_NEAR(ceiling.t, 3.5, 1e-12);
  EXPECT_EQ(ceiling.surface, 5);
  EXPECT_EQ(scene.CastRay(Eigen::Vector3d(9, 0, 1), Eigen::Vector3d::UnitX()).surface, -1);
}

}  // namespace
}  // namespace vio::tools
