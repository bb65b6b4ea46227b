#include "vio/simulator/render.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include <glog/logging.h>

#include <opencv2/core/utility.hpp>

#include "hash.h"
#include "vio/frontend/camera_model.h"
#include "vio/simulator/sensor.h"

namespace vio::tools {
namespace {

constexpr std::array<float, 4> kCellSizes = {0.8f, 0.3f, 0.12f, 0.05f};  // [m], coarse to fine
constexpr std::array<float, 4> kInverseCellSizes = {1.0f / 0.8f, 1.0f / 0.3f, 1.0f / 0.12f, 1.0f / 0.05f};
// Of 8 cells of each level, this many hold a rectangle.
constexpr std::array<std::uint64_t, 4> kRectangleEighths = {6, 4, 3, 2};
constexpr float kCellOffset = 4096.0f;  // keeps cell coordinates positive ...
constexpr double kMaxCoordinate = 150.0;  // ... for rooms within this distance of the origin [m]
constexpr float kMinCellPixels = 3.0f;  // finer texture levels are skipped (anti-aliasing)

struct SurfaceHit {
  float t = std::numeric_limits<float>::infinity();  // [m]
  int surface = -1;
  int axis = 0;  // normal axis of the hit face
};

// The nearest of: the room face the ray leaves through, the listed boxes
// (slab test). `d` has no zero component.
inline SurfaceHit CastRay(const Eigen::Vector3f& room_min, const Eigen::Vector3f& room_max,
                          const std::vector<Eigen::AlignedBox3f>& all_boxes, const int* boxes, int num_boxes,
                          const Eigen::Vector3f& p_w_c, const Eigen::Vector3f& d) {
  const Eigen::Vector3f inv = d.cwiseInverse();
  SurfaceHit hit;
  for (int a = 0; a < 3; ++a) {
    const bool positive = d[a] > 0.0f;
    const float t = ((positive ? room_max[a] : room_min[a]) - p_w_c[a]) * inv[a];
    if (t < hit.t) hit = {t, 2 * a + (positive ? 1 : 0), a};
  }
  for (int k = 0; k < num_boxes; ++k) {
    const Eigen::AlignedBox3f& box = all_boxes[boxes[k]];
    const Eigen::Vector3f t1 = (box.min() - p_w_c).cwiseProduct(inv);
    const Eigen::Vector3f t2 = (box.max() - p_w_c).cwiseProduct(inv);
    int axis = 0;
    const float t_enter = t1.cwiseMin(t2).maxCoeff(&axis);
    const float t_exit = t1.cwiseMax(t2).minCoeff();
    if (t_enter <= t_exit && t_enter > 0.0f && t_enter < hit.t) {
      hit = {t_enter, 6 + 6 * boxes[k] + 2 * axis + (inv[axis] > 0.0f ? 0 : 1), axis};
    }
  }
  return hit;
}

}  // namespace

SceneRenderer::SceneRenderer(const Scene& scene, const CameraCalibration& camera,
                             const RenderOptions& options, const ImageTextures* textures)
    : scene_(scene),
      camera_(camera),
      options_(options),
      image_textures_(textures != nullptr && !textures->empty() ? textures : nullptr),
      room_min_(scene.room.min().cast<float>()),
      room_max_(scene.room.max().cast<float>()) {
  if (!(scene.room.min().cwiseAbs().maxCoeff() < kMaxCoordinate && scene.room.max().cwiseAbs().maxCoeff() < kMaxCoordinate)) {
    throw std::invalid_argument("renderer: the room must lie within " + std::to_string(kMaxCoordinate) +
                                " m of the world origin (texture cell coordinates)");
  }
  for (const Eigen::AlignedBox3d& box : scene.boxes) boxes_.emplace_back(box.cast<float>());
  BuildRayTable();
  BuildTextures();
}

void SceneRenderer::BuildRayTable() {
  const frontend::CameraModel model(camera_);
  const int width = camera_.width, height = camera_.height;
  rays_c_.assign(static_cast<std::size_t>(width) * height, Eigen::Vector3f::Zero());
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const std::optional<Eigen::Vector3d> ray = model.Unproject(Eigen::Vector2d(u, v));
      if (ray) rays_c_[static_cast<std::size_t>(v) * width + u] = ray->cast<float>();
    }
  }
  tiles_x_ = (width + kTileSize - 1) / kTileSize;
  tiles_y_ = (height + kTileSize - 1) / kTileSize;
  tiles_.assign(tiles_x_ * tiles_y_, Tile());
  for (std::size_t t = 0; t < tiles_.size(); ++t) {
    Eigen::Vector3f sum = Eigen::Vector3f::Zero();
    ForEachPixel(static_cast<int>(t), [&](int, int, std::size_t index) { sum += rays_c_[index]; });
    tiles_[t].axis_c = sum.normalized();
    float min_cos = 1.0f;
    ForEachPixel(static_cast<int>(t), [&](int, int, std::size_t index) {
      if (!rays_c_[index].isZero()) min_cos = std::min(min_cos, tiles_[t].axis_c.dot(rays_c_[index]));
    });
    tiles_[t].half_angle = std::acos(std::clamp(min_cos, -1.0f, 1.0f)) + 1e-3f;
  }
}

void SceneRenderer::BuildTextures() {
  const int num_surfaces = 6 + 6 * static_cast<int>(scene_.boxes.size());
  textures_.resize(num_surfaces);
  for (int surface = 0; surface < num_surfaces; ++surface) {
    const std::uint64_t surface_key = Mix(options_.texture_seed * 0x100000001b3ULL + static_cast<std::uint64_t>(surface));
    SurfaceTexture& texture = textures_[surface];
    texture.base_grey = 80.0f + static_cast<float>(surface_key % 96);
    for (std::size_t level = 0; level < kCellSizes.size(); ++level) {
      const std::uint64_t level_key = Mix(surface_key + level);
      // Shifted grids, so that edges of different levels do not line up; the
      // large constant keeps cell coordinates positive (truncation = floor).
      texture.levels[level] = {level_key, kCellOffset + UnitFromBits(level_key),
                               kCellOffset + UnitFromBits(level_key >> 8)};
    }
    if (image_textures_ == nullptr) continue;
    const std::uint64_t image_key = Mix(surface_key ^ 0x696d616765ULL);
    texture.image = image_key % image_textures_->pyramids.size();
    const cv::Mat& level0 = image_textures_->pyramids[texture.image][0];
    // Large positive offsets keep texel coordinates positive (mirrored repeat).
    texture.image_x = static_cast<float>(2 * kCellOffset * level0.cols + (image_key >> 16) % level0.cols);
    texture.image_y = static_cast<float>(2 * kCellOffset * level0.rows + (image_key >> 32) % level0.rows);
    texture.swap_axes = (image_key >> 8) & 1u;
    texture.sign_a = (image_key >> 9) & 1u ? -1.0f : 1.0f;
    texture.sign_b = (image_key >> 10) & 1u ? -1.0f : 1.0f;
  }
}

float SceneRenderer::ImageGrey(const SurfaceTexture& texture, float a, float b, float footprint_m) const {
  const float inverse_texel = static_cast<float>(1.0 / image_textures_->texel_m);
  float x = texture.sign_a * a * inverse_texel, y = texture.sign_b * b * inverse_texel;
  if (texture.swap_axes) std::swap(x, y);
  return image_textures_->Sample(texture.image, texture.image_x + x, texture.image_y + y, footprint_m * inverse_texel);
}

float SceneRenderer::SurfaceGrey(int surface, float a, float b, float footprint_m) const {
  const SurfaceTexture& texture = textures_[surface];
  if (image_textures_ != nullptr) return ImageGrey(texture, a, b, footprint_m);
  float grey = texture.base_grey;
  for (std::size_t level = 0; level < kCellSizes.size(); ++level) {
    if (kCellSizes[level] < kMinCellPixels * footprint_m) break;
    const TextureLevel& tl = texture.levels[level];
    const float ga = a * kInverseCellSizes[level] + tl.offset_a;
    const float gb = b * kInverseCellSizes[level] + tl.offset_b;
    const auto i = static_cast<std::uint64_t>(ga), j = static_cast<std::uint64_t>(gb);
    const std::uint64_t h = Mix(tl.key ^ (i * 0x9e3779b97f4a7c15ULL) ^ (j * 0xc2b2ae3d27d4eb4fULL));
    if ((h & 7u) >= kRectangleEighths[level]) continue;
    const float x0 = 0.5f * UnitFromBits(h >> 8), y0 = 0.5f * UnitFromBits(h >> 16);
    const float x1 = x0 + (0.3f + 0.7f * UnitFromBits(h >> 24)) * (1.0f - x0);
    const float y1 = y0 + (0.3f + 0.7f * UnitFromBits(h >> 32)) * (1.0f - y0);
    const float fa = ga - static_cast<float>(i), fb = gb - static_cast<float>(j);
    if (fa < x0 || fa > x1 || fb < y0 || fb > y1) continue;
    const float shade = static_cast<float>((h >> 41) & 63u);
    grey = ((h >> 40) & 1u) ? 180.0f + shade : 15.0f + shade;
  }
  return grey;
}

// Boxes whose bounding sphere meets each tile's cone of rays, as a flat list:
// entry [tile * (B + 1)] is the count, the indices follow.
std::vector<int> SceneRenderer::BoxesPerTile(const Eigen::Isometry3d& T_w_c) const {
  const int stride = static_cast<int>(boxes_.size()) + 1;
  std::vector<int> lists(tiles_.size() * stride, 0);
  const Eigen::Isometry3d T_c_w = T_w_c.inverse();
  for (std::size_t b = 0; b < scene_.boxes.size(); ++b) {
    const Eigen::Vector3f center_c = (T_c_w * scene_.boxes[b].center()).cast<float>();
    const float radius = 0.5f * static_cast<float>(scene_.boxes[b].sizes().norm());
    const float distance = center_c.norm();
    const bool surrounds = distance <= radius;
    const float spread = surrounds ? 0.0f : std::asin(radius / distance);
    for (std::size_t t = 0; t < tiles_.size(); ++t) {
      const float angle = surrounds ? 0.0f
                                    : std::acos(std::clamp(tiles_[t].axis_c.dot(center_c) / distance, -1.0f, 1.0f));
      if (angle > tiles_[t].half_angle + spread) continue;
      int& count = lists[t * stride];
      lists[t * stride + 1 + count++] = static_cast<int>(b);
    }
  }
  return lists;
}

void SceneRenderer::Render(const Eigen::Isometry3d& T_w_c, std::uint64_t noise_key, cv::Mat* image) const {
  CHECK(image != nullptr);
  cv::Mat radiance;
  AddRadiance(T_w_c, 1.0f, &radiance);
  SensorOptions sensor;
  sensor.read_noise = options_.image_noise_sigma;
  sensor.shot_noise = 0.0;
  ExposeImage(radiance, 1.0, cv::Mat(), sensor, noise_key, image);
}

void SceneRenderer::AddRadiance(const Eigen::Isometry3d& T_w_c, float weight, cv::Mat* radiance) const {
  CHECK(radiance != nullptr);
  if (radiance->rows != camera_.height || radiance->cols != camera_.width || radiance->type() != CV_32FC1) {
    *radiance = cv::Mat::zeros(camera_.height, camera_.width, CV_32FC1);
  }
  const std::vector<int> lists = BoxesPerTile(T_w_c);
  const int stride = static_cast<int>(boxes_.size()) + 1;
  const Eigen::Matrix3f R_w_c = T_w_c.linear().cast<float>();
  const Eigen::Vector3f p_w_c = T_w_c.translation().cast<float>();
  cv::parallel_for_(cv::Range(0, static_cast<int>(tiles_.size())), [&](const cv::Range& range) {
    for (int t = range.start; t < range.end; ++t) {
      RenderTile(t, R_w_c, p_w_c, &lists[t * stride + 1], lists[t * stride], weight, radiance);
    }
  });
}

void SceneRenderer::RenderTile(int tile, const Eigen::Matrix3f& R_w_c, const Eigen::Vector3f& p_w_c,
                               const int* boxes, int num_boxes, float weight, cv::Mat* radiance) const {
  const float focal = static_cast<float>(camera_.intrinsics[0]);
  ForEachPixel(tile, [&](int u, int v, std::size_t index) {
    const Eigen::Vector3f& ray_c = rays_c_[index];
    if (ray_c.isZero()) return;  // no light where the lens model has no ray
    Eigen::Vector3f d = R_w_c * ray_c;
    for (int a = 0; a < 3; ++a) {
      if (std::abs(d[a]) < 1e-9f) d[a] = 1e-9f;
    }
    const SurfaceHit hit = CastRay(room_min_, room_max_, boxes_, boxes, num_boxes, p_w_c, d);
    const Eigen::Vector3f p = p_w_c + hit.t * d;
    const int a1 = (hit.axis + 1) % 3, a2 = (hit.axis + 2) % 3;
    const float footprint = hit.t / (focal * std::max(std::abs(d[hit.axis]), 0.2f));
    radiance->ptr<float>(v)[u] += weight * SurfaceGrey(hit.surface, p[a1], p[a2], footprint);
  });
}

}  // namespace vio::tools
