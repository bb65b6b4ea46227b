#pragma once
// Renders the simulator's scene as 8-bit grey images through a real camera
// model (intrinsics and distortion).
//
// Each pixel's unit ray (camera frame) is computed once by undistorting the
// pixel centre. Per frame, rays are rotated into the world and cast against
// the room (leaving a convex box: one division per axis) and the boxes (slab
// test), where only the boxes whose bounding sphere meets a 16 x 16 pixel
// tile's cone of rays are tested for that tile. With real image textures
// (texture.h) each surface shows a hashed image at a hashed offset and
// orientation; without, the hit surface is textured
// procedurally and deterministically: on a base grey, four levels of cells
// (0.8, 0.3, 0.12, 0.05 m) each hold, with probability 6/8, 4/8, 3/8, 2/8, one rectangle of
// a dark or bright grey at a hashed position and size, finer levels on top;
// levels whose cells would be smaller than 3 pixels are skipped (cheap
// anti-aliasing). Plenty of corners for FAST/BRISK, no per-pixel allocation.
// Tiles are rendered in parallel (each pixel is a function of its ray only).
#include <array>
#include <algorithm>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "vio/estimator/types.h"
#include "vio/simulator/scene.h"
#include "vio/simulator/texture.h"

namespace vio::tools {

struct RenderOptions {
  /// Standard deviation of the per-pixel image noise [grey levels].
  double image_noise_sigma = 1.0;
  /// Seed of the surface textures (same seed, same textures).
  std::uint64_t texture_seed = 1;
};

class SceneRenderer {
 public:
  /// Precomputes the ray table of `camera`. The scene (and `textures`, when
  /// given and not empty: real image textures instead of procedural ones)
  /// must outlive the renderer. Throws std::invalid_argument when the room
  /// extends beyond 150 m from the world origin.
  SceneRenderer(const Scene& scene, const CameraCalibration& camera, const RenderOptions& options,
                const ImageTextures* textures = nullptr);

  /// Renders into `image` (CV_8UC1, width x height; reallocated when needed)
  /// the view of a camera at T_w_c; `noise_key` selects the noise pattern
  /// (use a different one per image).
  void Render(const Eigen::Isometry3d& T_w_c, std::uint64_t noise_key, cv::Mat* image) const;

  /// Adds `weight` times the scene's grey levels (no noise) seen from T_w_c
  /// to `radiance` (CV_32FC1, width x height; zero-initialized when it is
  /// not that yet).
  void AddRadiance(const Eigen::Isometry3d& T_w_c, float weight, cv::Mat* radiance) const;

  /// Grey level [0, 255] of surface `surface` (see scene.h) at in-plane
  /// coordinates (a, b) [m], seen with a pixel footprint of `footprint_m`.
  float SurfaceGrey(int surface, float a, float b, float footprint_m) const;

 private:
  struct Tile {
    Eigen::Vector3f axis_c;  // central ray
    float half_angle = 0.0f; // [rad]
  };
  struct TextureLevel {
    std::uint64_t key = 0;                  // hash key of the level's cells
    float offset_a = 0.0f, offset_b = 0.0f; // grid shift [cells]
  };
  struct SurfaceTexture {
    float base_grey = 128.0f;
    std::array<TextureLevel, 4> levels;  // coarse to fine
    std::size_t image = 0;                   // image texture: which image
    float image_x = 0.0f, image_y = 0.0f;    // texel offset
    bool swap_axes = false;                  // (a, b) -> (y, x)
    float sign_a = 1.0f, sign_b = 1.0f;      // mirrored axes
  };
  void BuildRayTable();
  void BuildTextures();
  /// Calls f(u, v, row-major index) for every pixel of a tile.
  template <class F>
  void ForEachPixel(int tile, F f) const {
    const int x0 = (tile % tiles_x_) * kTileSize, y0 = (tile / tiles_x_) * kTileSize;
    for (int v = y0; v < std::min(camera_.height, y0 + kTileSize); ++v) {
      for (int u = x0; u < std::min(camera_.width, x0 + kTileSize); ++u) {
        f(u, v, static_cast<std::size_t>(v) * camera_.width + u);
      }
    }
  }

  std::vector<int> BoxesPerTile(const Eigen::Isometry3d& T_w_c) const;
  void RenderTile(int tile, const Eigen::Matrix3f& R_w_c, const Eigen::Vector3f& p_w_c,
                  const int* boxes, int num_boxes, float weight, cv::Mat* radiance) const;
  float ImageGrey(const SurfaceTexture& texture, float a, float b, float footprint_m) const;

  static constexpr int kTileSize = 16;  // [px]

  const Scene& scene_;
  CameraCalibration camera_;
  RenderOptions options_;
  const ImageTextures* image_textures_ = nullptr;  // null or empty: procedural
  Eigen::Vector3f room_min_, room_max_;
  int tiles_x_ = 0, tiles_y_ = 0;
  std::vector<Eigen::Vector3f> rays_c_;  // row-major, unit; zero when not undistortable
  std::vector<Tile> tiles_;
  std::vector<Eigen::AlignedBox3f> boxes_;
  std::vector<SurfaceTexture> textures_;
};

}  // namespace vio::tools
