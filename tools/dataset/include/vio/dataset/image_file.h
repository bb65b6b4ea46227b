#pragma once
// Reading a camera image file as 8-bit grey.
#include <string>
#include <vector>

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
/// Any other file goes to ImageRead.
cv::Mat ReadGreyImage(const std::string& path);

// OpenCV's image codecs (cv::imread, cv::imdecode, cv::imwrite, same
// arguments and results). `vio` does not link libopencv_imgcodecs: its
// dependencies (GDAL, GDCM, libheif, Poppler... 130 libraries) made every
// start of the process cost 0.39e9 instructions in the dynamic loader and
// their constructors. It is loaded by the first call of one of these; they
// throw std::runtime_error naming the library when it cannot be loaded.
cv::Mat ImageRead(const std::string& path, int flags);
cv::Mat ImageDecode(const cv::Mat& bytes, int flags);
bool ImageWrite(const std::string& path, const cv::Mat& image, const std::vector<int>& params = {});

}  // namespace vio::tools
