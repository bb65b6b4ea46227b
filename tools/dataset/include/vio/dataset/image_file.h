#pragma once
// Reading a camera image file as 8-bit grey.
#include <string>

#include <opencv2/core.hpp>

namespace vio::tools {

/// The image in `path` as CV_8UC1, the same pixels as cv::imread(path,
/// cv::IMREAD_GRAYSCALE); empty when the file cannot be read or decoded
/// (missing, truncated, a chunk whose CRC does not match, no image).
/// An 8-bit grey, non-interlaced PNG (the EuRoC images) is decoded by libpng
/// directly, without checking zlib's Adler-32 of the decompressed rows: the
/// chunk CRCs still cover every byte of the file, and on the EuRoC PNGs
/// (stored without compression) the Adler-32 took 7 % of the decoding.
/// Any other file goes to cv::imread.
cv::Mat ReadGreyImage(const std::string& path);

}  // namespace vio::tools
