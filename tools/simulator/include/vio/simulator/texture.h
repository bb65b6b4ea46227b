#pragma once
// Surface textures cut from real grey images (e.g. the EuRoC clips in
// ../shared/data), read in place when the simulator starts: nothing is
// copied into the output beyond the rendered frames.
//
// Each image is cropped to its centre (the real lens' vignetting stays out of
// the texture), converted to float and kept as a mipmap pyramid. A surface
// maps its in-plane coordinates [m] to texels of one image at texel_m per
// texel, with a hashed image, offset and orientation per surface, repeated
// mirrored, sampled bilinearly at the pyramid level of the pixel footprint.
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace vio::tools {

struct ImageTextureOptions {
  /// Folders of real grey images, comma-separated (an ASL folder means its
  /// mav0/cam0/data); empty: procedural textures.
  std::string dirs;
  /// Size of one texel on a surface [m].
  double texel_m = 0.006;
  /// Images used per folder at most, spread evenly over its sorted files.
  int max_images_per_dir = 4;
  /// Fraction of each image's width and height kept around its centre (0, 1].
  double crop = 0.8;
};

/// Real image content for the renderer: one mipmap pyramid per image.
struct ImageTextures {
  std::vector<std::vector<cv::Mat>> pyramids;  ///< CV_32FC1, level 0 first
  double texel_m = 0.006;                      ///< [m]

  bool empty() const { return pyramids.empty(); }
  /// Grey level of image `image` at texel (x, y) of level 0, seen with a
  /// footprint of `footprint_texels` texels per pixel.
  float Sample(std::size_t image, float x, float y, float footprint_texels) const;
};

/// Throws std::invalid_argument naming the first option out of range.
void CheckImageTextureOptions(const ImageTextureOptions& options);

/// Loads the textures of `options.dirs`. A folder that is missing or holds
/// no readable .png/.jpg image is skipped with a warning; when no folder
/// gave an image the result is empty (procedural textures) and a warning
/// says so. Throws std::invalid_argument for texel_m <= 0, crop outside
/// (0, 1] or max_images_per_dir < 1.
ImageTextures LoadImageTextures(const ImageTextureOptions& options);

}  // namespace vio::tools
