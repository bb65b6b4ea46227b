// Rendered images agree with the scene geometry and the camera model, carry
// plenty of corners and are deterministic.
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>

#include "vio/frontend/camera_model.h"
#include "vio/simulator/render.h"
#include "vio/simulator/simulator.h"

namespace vio::tools {
namespace {

struct RenderScene {
  Scene scene;
  CameraCalibration camera;
  Eigen::Isometry3d T_w_c;
};

RenderScene MakeRenderScene() {
  SimulatorOptions options;
  options.duration_s = 12.0;
  options.camera_output = SimCameraOutput::kImages;
  RenderScene world;
  Simulation sim = BuildSimulation(options);
  world.scene = std::move(sim.scene);
  world.camera = sim.dataset.cameras[0];
  world.T_w_c = sim.frames.back().T_w_b * world.camera.T_b_c;
  return world;
}

// For sampled pixels, cast the pixel's ray (undistorted with the camera
// model) against the scene in double precision and texture the hit: the
// rendered grey must match except at texture edges.
TEST(SceneRendererTest, PixelsShowTheSurfaceTheirRayHits) {
  const RenderScene world = MakeRenderScene();
  RenderOptions options;
  options.image_noise_sigma = 0.0;
  const SceneRenderer renderer(world.scene, world.camera, options);
  cv::Mat image;
  renderer.Render(world.T_w_c, 0, &image);
  const frontend::CameraModel model(world.camera);
  int agree = 0, total = 0;
  for (int v = 1; v < image.rows; v += 7) {
    for (int u = 2; u < image.cols; u += 7) {
      const Eigen::Vector3d ray_w = world.T_w_c.linear() * model.Unproject(Eigen::Vector2d(u, v)).value();
      const Scene::RayHit hit = world.scene.CastRay(world.T_w_c.translation(), ray_w);
      ASSERT_GE(hit.surface, 0);
      const Eigen::Vector3d p_w = world.T_w_c.translation() + hit.t * ray_w;
      const int axis = hit.surface % 6 / 2;
      const float footprint = static_cast<float>(
          hit.t / (world.camera.intrinsics[0] * std::max(std::abs(ray_w[axis]), 0.2)));
      const float expected = renderer.SurfaceGrey(hit.surface, static_cast<float>(p_w[(axis + 1) % 3]),
                                                  static_cast<float>(p_w[(axis + 2) % 3]), footprint);
      agree += std::abs(image.at<std::uint8_t>(v, u) - expected) <= 1.0f;
      ++total;
    }
  }
  EXPECT_GT(agree, 0.97 * total) << agree << " of " << total;
}

TEST(SceneRendererTest, ImagesHavePlentyOfCornersAndAreDeterministic) {
  const RenderScene world = MakeRenderScene();
  const SceneRenderer renderer(world.scene, world.camera, RenderOptions());
  cv::Mat a, b, c;
  renderer.Render(world.T_w_c, 7, &a);
  renderer.Render(world.T_w_c, 7, &b);
  renderer.Render(world.T_w_c, 8, &c);
  ASSERT_EQ(a.type(), CV_8UC1);
  ASSERT_EQ(a.cols, 752);
  ASSERT_EQ(a.rows, 480);
  EXPECT_EQ(cv::countNonZero(a != b), 0);
  EXPECT_GT(cv::countNonZero(a != c), 0);  // the noise pattern changes with the key
  std::vector<cv::KeyPoint> corners;
  cv::FAST(a, corners, 20, true);
  EXPECT_GT(corners.size(), 500u);
  cv::Scalar mean, stddev;
  cv::meanStdDev(a, mean, stddev);
  EXPECT_GT(stddev[0], 25.0);
}

}  // namespace
}  // namespace vio::tools
