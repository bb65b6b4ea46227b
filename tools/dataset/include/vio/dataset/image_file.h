#pragma once
// Reading a camera image file as 8-bit grey.
#include <string>

#include <opencv2/core.hpp>

namespace vio::tools {

/// The image in `path` as CV_8UC1, the same pixels as cv::imread(path,
/// cv::IMREAD_GRAYSCALE); empty when the file cannot be read or decoded
/// (missing, truncated, a chunk whose CRC does not match, no image).
/// An 8-bit grey, non-interlaced PNG (the EuRoC images) is decoded here:
/// every chunk's CRC checked, the image data inflated by libdeflate (zlib's
/// Adler-32 checked) and its row filters reversed, 2.7x faster than libpng on
/// the EuRoC images, whose Paeth and average filters dominate (libspng: 1.2x
/// slower than libpng).
/// Any other file goes to cv::imread.
cv::Mat ReadGreyImage(const std::string& path);

}  // namespace vio::tools
