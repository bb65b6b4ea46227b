#include "vio/dataset/image_file.h"

#include <png.h>

#include <csetjmp>
#include <cstdio>
#include <vector>

#include <opencv2/imgcodecs.hpp>

namespace vio::tools {
namespace {

/// The PNG signature's length [bytes].
constexpr size_t kPngSignatureBytes = 8;
/// Larger images go to cv::imread, which refuses them (its own limit) [pixels].
constexpr double kMaxLibpngImagePixels = 1 << 30;

/// A libpng reader on an open file, released on every path.
struct PngFile {
  std::FILE* file = nullptr;
  png_structp png = nullptr;
  png_infop info = nullptr;
  ~PngFile() {
    if (png != nullptr) png_destroy_read_struct(&png, info != nullptr ? &info : nullptr, nullptr);
    if (file != nullptr) std::fclose(file);
  }
};

// libpng reports errors by longjmp to the last setjmp: the functions holding
// one have only trivially destructible locals.

// Reads the header; true for an 8-bit grey, non-interlaced image (its size
// in *width, *height).
bool IsPlainGrey(png_structp png, png_infop info, png_uint_32* width, png_uint_32* height) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_info(png, info);
  int depth = 0, color = 0, interlace = 0;
  png_get_IHDR(png, info, width, height, &depth, &color, &interlace, nullptr, nullptr);
  return depth == 8 && color == PNG_COLOR_TYPE_GRAY && interlace == PNG_INTERLACE_NONE &&
         !png_get_valid(png, info, PNG_INFO_tRNS) &&
         static_cast<double>(*width) * *height <= kMaxLibpngImagePixels;
}

// Decodes the rows; false on a libpng error (truncated data, a bad CRC).
bool ReadRows(png_structp png, png_bytepp rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_read_image(png, rows);
  png_read_end(png, nullptr);
  return true;
}

void IgnoreWarning(png_structp, png_const_charp) {}

}  // namespace

cv::Mat ReadGreyImage(const std::string& path) {
  PngFile f;
  f.file = std::fopen(path.c_str(), "rb");
  if (f.file == nullptr) return cv::Mat();
  png_byte signature[kPngSignatureBytes];
  if (std::fread(signature, 1, kPngSignatureBytes, f.file) != kPngSignatureBytes ||
      png_sig_cmp(signature, 0, kPngSignatureBytes) != 0) {
    return cv::imread(path, cv::IMREAD_GRAYSCALE);
  }
  f.png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, IgnoreWarning);
  if (f.png == nullptr) return cv::Mat();
  f.info = png_create_info_struct(f.png);
  if (f.info == nullptr) return cv::Mat();
  png_init_io(f.png, f.file);
  png_set_sig_bytes(f.png, static_cast<int>(kPngSignatureBytes));
  png_set_option(f.png, PNG_IGNORE_ADLER32, PNG_OPTION_ON);
  png_uint_32 width = 0, height = 0;
  if (!IsPlainGrey(f.png, f.info, &width, &height)) return cv::imread(path, cv::IMREAD_GRAYSCALE);
  cv::Mat image(static_cast<int>(height), static_cast<int>(width), CV_8UC1);
  std::vector<png_bytep> rows(height);
  for (png_uint_32 y = 0; y < height; ++y) rows[y] = image.ptr<png_byte>(static_cast<int>(y));
  if (!ReadRows(f.png, rows.data())) return cv::Mat();
  return image;
}

}  // namespace vio::tools
