#include "vio/simulator/texture.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include <glog/logging.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "vio/dataset/image_file.h"

namespace vio::tools {
namespace {

namespace fs = std::filesystem;

constexpr int kMinLevelSize = 16;  // coarsest pyramid level, smaller side [texels]

// Index i of a signal of length n repeated mirrored (period 2 n); i >= 0.
inline int Mirror(int i, int n) {
  const int m = i % (2 * n);
  return m < n ? m : 2 * n - 1 - m;
}

std::vector<std::string> Split(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!item.empty()) items.push_back(item);
  }
  return items;
}

std::vector<fs::path> ImageFiles(const fs::path& dir) {
  std::vector<fs::path> files;
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    const std::string ext = entry.path().extension().string();
    if (entry.is_regular_file() && (ext == ".png" || ext == ".jpg" || ext == ".jpeg")) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::vector<cv::Mat> Pyramid(const cv::Mat& grey, double crop) {
  const int w = std::max(kMinLevelSize, static_cast<int>(grey.cols * crop));
  const int h = std::max(kMinLevelSize, static_cast<int>(grey.rows * crop));
  const cv::Rect centre((grey.cols - std::min(w, grey.cols)) / 2, (grey.rows - std::min(h, grey.rows)) / 2,
                        std::min(w, grey.cols), std::min(h, grey.rows));
  std::vector<cv::Mat> levels(1);
  grey(centre).convertTo(levels[0], CV_32F);
  while (std::min(levels.back().cols, levels.back().rows) >= 2 * kMinLevelSize) {
    cv::Mat next;
    cv::pyrDown(levels.back(), next);
    levels.push_back(next);
  }
  return levels;
}

}  // namespace

void CheckImageTextureOptions(const ImageTextureOptions& options) {
  if (!(options.texel_m > 0.0)) {
    throw std::invalid_argument("texel_size must be positive [m], got " + std::to_string(options.texel_m));
  }
  if (!(options.crop > 0.0 && options.crop <= 1.0)) {
    throw std::invalid_argument("texture crop must be in (0, 1], got " + std::to_string(options.crop));
  }
  if (options.max_images_per_dir < 1) throw std::invalid_argument("texture: need at least one image per folder");
}

float ImageTextures::Sample(std::size_t image, float x, float y, float footprint_texels) const {
  const std::vector<cv::Mat>& levels = pyramids[image];
  int level = 0;
  if (footprint_texels > 1.0f) {
    level = std::min(static_cast<int>(levels.size()) - 1, static_cast<int>(std::log2(footprint_texels)));
  }
  const cv::Mat& texture = levels[level];
  const float scale = 1.0f / static_cast<float>(1 << level);
  const float xs = x * scale - 0.5f, ys = y * scale - 0.5f;
  const float fx0 = std::floor(xs), fy0 = std::floor(ys);
  const float fx = xs - fx0, fy = ys - fy0;
  const int x0 = static_cast<int>(fx0), y0 = static_cast<int>(fy0);
  const int xa = Mirror(x0, texture.cols), xb = Mirror(x0 + 1, texture.cols);
  const float* row_a = texture.ptr<float>(Mirror(y0, texture.rows));
  const float* row_b = texture.ptr<float>(Mirror(y0 + 1, texture.rows));
  const float top = row_a[xa] + fx * (row_a[xb] - row_a[xa]);
  const float bottom = row_b[xa] + fx * (row_b[xb] - row_b[xa]);
  return top + fy * (bottom - top);
}

ImageTextures LoadImageTextures(const ImageTextureOptions& options) {
  CheckImageTextureOptions(options);
  ImageTextures textures;
  textures.texel_m = options.texel_m;
  for (const std::string& dir : Split(options.dirs)) {
    const fs::path asl_cam0 = fs::path(dir) / "mav0" / "cam0" / "data";
    const fs::path folder = fs::is_directory(asl_cam0) ? asl_cam0 : fs::path(dir);
    const std::vector<fs::path> files = ImageFiles(folder);
    const std::size_t count = std::min<std::size_t>(files.size(), options.max_images_per_dir);
    std::size_t loaded = 0;
    for (std::size_t k = 0; k < count; ++k) {
      const cv::Mat grey = ImageRead(files[k * files.size() / count].string(), cv::IMREAD_GRAYSCALE);
      if (grey.empty()) continue;
      textures.pyramids.push_back(Pyramid(grey, options.crop));
      ++loaded;
    }
    if (loaded == 0) {
      LOG(WARNING) << "texture: " << folder.string()
                   << (fs::is_directory(folder) ? ": no readable .png/.jpg image" : ": no such folder");
    }
  }
  if (textures.empty() && !Split(options.dirs).empty()) {
    LOG(WARNING) << "texture: no real image found in '" << options.dirs
                 << "'; rendering with procedural textures instead";
  }
  return textures;
}

}  // namespace vio::tools
