#include "vio/dataset/image_file.h"

#include <libdeflate.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include <opencv2/imgcodecs.hpp>

namespace vio::tools {
namespace {

/// The PNG signature.
constexpr unsigned char kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
/// Larger images go to cv::imread, which refuses them (its own limit) [pixels].
constexpr double kMaxDirectImagePixels = 1 << 30;
/// A chunk's length, type and CRC fields [bytes].
constexpr size_t kChunkOverhead = 12;

/// The bytes of the file, or nothing when it cannot be read.
std::optional<std::vector<unsigned char>> FileBytes(const std::string& path) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (file == nullptr) return std::nullopt;
  std::vector<unsigned char> bytes;
  unsigned char buffer[1 << 16];
  size_t got = 0;
  while ((got = std::fread(buffer, 1, sizeof(buffer), file.get())) > 0) bytes.insert(bytes.end(), buffer, buffer + got);
  if (std::ferror(file.get()) != 0) return std::nullopt;
  return bytes;
}

std::uint32_t BigEndian32(const unsigned char* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}

/// One chunk of a PNG file, inside its bytes.
struct Chunk {
  const unsigned char* type = nullptr;  ///< 4 bytes, then the data
  std::uint32_t length = 0;
  bool Is(const char* name) const { return std::memcmp(type, name, 4) == 0; }
  const unsigned char* data() const { return type + 4; }
};

/// The chunk at `offset`, empty when it runs past the end of the file or its CRC does not match.
std::optional<Chunk> ChunkAt(const std::vector<unsigned char>& bytes, size_t offset) {
  if (offset + kChunkOverhead > bytes.size()) return std::nullopt;
  Chunk chunk{&bytes[offset + 4], BigEndian32(&bytes[offset])};
  if (chunk.length > bytes.size() - offset - kChunkOverhead) return std::nullopt;
  const std::uint32_t crc = BigEndian32(chunk.data() + chunk.length);
  if (libdeflate_crc32(0, chunk.type, chunk.length + 4) != crc) return std::nullopt;
  return chunk;
}

/// The size of an 8-bit grey, non-interlaced PNG from its IHDR chunk (the
/// first); empty for any other kind of image.
std::optional<cv::Size> PlainGreySize(const std::vector<unsigned char>& bytes) {
  const std::optional<Chunk> header = ChunkAt(bytes, sizeof(kPngSignature));
  if (!header || !header->Is("IHDR") || header->length != 13) return std::nullopt;
  const unsigned char* d = header->data();
  const std::uint32_t width = BigEndian32(d), height = BigEndian32(d + 4);
  const bool grey = d[8] == 8 && d[9] == 0 && d[10] == 0 && d[11] == 0 && d[12] == 0;
  if (!grey || width == 0 || height == 0 || static_cast<double>(width) * height > kMaxDirectImagePixels) {
    return std::nullopt;
  }
  return cv::Size(static_cast<int>(width), static_cast<int>(height));
}

/// The concatenated IDAT data of a file whose every chunk is whole and
/// matches its CRC, up to IEND. Empty (nullopt) when a chunk is damaged or
/// missing, or an unknown critical chunk is met; `transparency` is set when
/// a tRNS chunk is.
std::optional<std::vector<unsigned char>> ImageData(const std::vector<unsigned char>& bytes, bool* transparency) {
  std::vector<unsigned char> data;
  size_t offset = sizeof(kPngSignature);
  while (true) {
    const std::optional<Chunk> chunk = ChunkAt(bytes, offset);
    if (!chunk) return std::nullopt;
    offset += kChunkOverhead + chunk->length;
    if (chunk->Is("IEND")) return data;
    if (chunk->Is("IDAT")) {
      data.insert(data.end(), chunk->data(), chunk->data() + chunk->length);
    } else if (chunk->Is("tRNS")) {
      *transparency = true;
    } else if ((chunk->type[0] & 0x20) == 0 && !chunk->Is("IHDR")) {
      return std::nullopt;  // a critical chunk a grey image does not have
    }
  }
}

// The PNG filters reversed on 8-bit grey pixels (one byte per pixel). Each
// row is one serial chain (a pixel needs the one left of it decoded), so two
// rows are decoded together, the second one pixel behind the first: two
// independent chains, about 1.5x the rate of one on the EuRoC images.

/// The predictor of filter type F from the decoded left, above and upper-left
/// pixels; Paeth's written so that the compiler selects without branches (the
/// choice is data-dependent noise), ties going to left, then above, as the PNG
/// specification says.
template <int F>
int Predict(int left, int above, int up_left) {
  if constexpr (F == 0) return 0;
  if constexpr (F == 1) return left;
  if constexpr (F == 2) return above;
  if constexpr (F == 3) return (left + above) >> 1;
  if constexpr (F == 4) {
    const int p_left = std::abs(above - up_left), p_above = std::abs(left - up_left),
              p_up_left = std::abs(left + above - 2 * up_left);
    const int second = p_above <= p_up_left ? above : up_left;
    const int second_distance = p_above <= p_up_left ? p_above : p_up_left;
    return p_left <= second_distance ? left : second;
  }
  return 0;
}

/// One row of filter type F; `up` is the previous row decoded (zeros for the first).
template <int F>
void UnfilterRow(const unsigned char* in, const unsigned char* up, unsigned char* out, int width) {
  int left = 0, up_left = 0;
  for (int x = 0; x < width; ++x) {
    const int above = up[x];
    left = (in[x] + Predict<F>(left, above, up_left)) & 0xff;
    out[x] = static_cast<unsigned char>(left);
    up_left = above;
  }
}

/// Two consecutive rows of filter types F0 and F1: pixel x of the first, then pixel x - 1 of the second.
template <int F0, int F1>
void UnfilterRowPair(const unsigned char* in0, const unsigned char* in1, const unsigned char* up, unsigned char* out0,
                     unsigned char* out1, int width) {
  int left0 = (in0[0] + Predict<F0>(0, up[0], 0)) & 0xff, up_left0 = up[0], left1 = 0, up_left1 = 0;
  out0[0] = static_cast<unsigned char>(left0);
  for (int x = 1; x <= width; ++x) {
    if (x < width) {
      const int above0 = up[x];
      left0 = (in0[x] + Predict<F0>(left0, above0, up_left0)) & 0xff;
      out0[x] = static_cast<unsigned char>(left0);
      up_left0 = above0;
    }
    const int above1 = out0[x - 1];
    left1 = (in1[x - 1] + Predict<F1>(left1, above1, up_left1)) & 0xff;
    out1[x - 1] = static_cast<unsigned char>(left1);
    up_left1 = above1;
  }
}

using RowFunction = void (*)(const unsigned char*, const unsigned char*, unsigned char*, int);
using RowPairFunction = void (*)(const unsigned char*, const unsigned char*, const unsigned char*, unsigned char*,
                                 unsigned char*, int);
constexpr int kFilterTypes = 5;
constexpr std::array<RowFunction, kFilterTypes> kRowFunctions = {UnfilterRow<0>, UnfilterRow<1>, UnfilterRow<2>,
                                                                 UnfilterRow<3>, UnfilterRow<4>};

template <int F0, int... F1>
constexpr std::array<RowPairFunction, kFilterTypes> PairsAfter(std::integer_sequence<int, F1...>) {
  return {UnfilterRowPair<F0, F1>...};
}
template <int... F0>
constexpr std::array<std::array<RowPairFunction, kFilterTypes>, kFilterTypes> AllPairs(std::integer_sequence<int, F0...>) {
  return {PairsAfter<F0>(std::make_integer_sequence<int, kFilterTypes>())...};
}
/// kRowPairFunctions[F0][F1]: the row pair of filter types F0, F1.
constexpr auto kRowPairFunctions = AllPairs(std::make_integer_sequence<int, kFilterTypes>());

/// The rows of `image` from the inflated, filtered scanlines (each its filter
/// type, then its pixels); false on a filter type PNG does not define.
bool Unfilter(const std::vector<unsigned char>& scanlines, cv::Mat* image) {
  const int width = image->cols;
  const std::vector<unsigned char> zeros(static_cast<size_t>(width), 0);
  const auto scanline = [&](int y) { return &scanlines[static_cast<size_t>(y) * (static_cast<size_t>(width) + 1)]; };
  for (int y = 0; y < image->rows;) {
    const unsigned char* in0 = scanline(y);
    const unsigned char* up = y > 0 ? image->ptr<unsigned char>(y - 1) : zeros.data();
    if (in0[0] >= kFilterTypes) return false;
    if (y + 1 == image->rows) {
      kRowFunctions[in0[0]](in0 + 1, up, image->ptr<unsigned char>(y), width);
      return true;
    }
    const unsigned char* in1 = scanline(y + 1);
    if (in1[0] >= kFilterTypes) return false;
    kRowPairFunctions[in0[0]][in1[0]](in0 + 1, in1 + 1, up, image->ptr<unsigned char>(y),
                                      image->ptr<unsigned char>(y + 1), width);
    y += 2;
  }
  return true;
}

/// Inflates the zlib stream (its Adler-32 checked) into exactly `size` bytes; false otherwise.
bool Inflate(const std::vector<unsigned char>& compressed, std::vector<unsigned char>* out, size_t size) {
  struct Free {
    void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
  };
  thread_local const std::unique_ptr<libdeflate_decompressor, Free> decompressor(libdeflate_alloc_decompressor());
  if (decompressor == nullptr) return false;
  out->resize(size);
  return libdeflate_zlib_decompress(decompressor.get(), compressed.data(), compressed.size(), out->data(), size,
                                    nullptr) == LIBDEFLATE_SUCCESS;
}

}  // namespace

cv::Mat ReadGreyImage(const std::string& path) {
  const std::optional<std::vector<unsigned char>> bytes = FileBytes(path);
  if (!bytes) return cv::Mat();
  const bool png = bytes->size() >= sizeof(kPngSignature) &&
                   std::memcmp(bytes->data(), kPngSignature, sizeof(kPngSignature)) == 0;
  const std::optional<cv::Size> size = png ? PlainGreySize(*bytes) : std::nullopt;
  if (!size) return ImageRead(path, cv::IMREAD_GRAYSCALE);
  bool transparency = false;
  const std::optional<std::vector<unsigned char>> compressed = ImageData(*bytes, &transparency);
  if (!compressed) return cv::Mat();
  if (transparency) return ImageRead(path, cv::IMREAD_GRAYSCALE);
  std::vector<unsigned char> scanlines;
  cv::Mat image(*size, CV_8UC1);
  const size_t scanline_bytes = static_cast<size_t>(size->height) * (static_cast<size_t>(size->width) + 1);
  if (!Inflate(*compressed, &scanlines, scanline_bytes) || !Unfilter(scanlines, &image)) return cv::Mat();
  return image;
}

}  // namespace vio::tools
