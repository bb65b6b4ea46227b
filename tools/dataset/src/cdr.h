#pragma once
// CDR, the byte layout of ROS 2 messages (OMG XCDR1 as ROS 2's default
// middleware writes it): a 4-byte encapsulation header (00 01: little endian,
// 00 00: big endian), then the fields, each primitive aligned to its own size
// counted from the end of the header; strings are a uint32 length (with the
// trailing NUL) and the bytes; sequences a uint32 count and the elements.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace vio::tools::ros2 {

/// Bad CDR bytes (truncated, an impossible length, an unknown encapsulation);
/// the message says what and at which byte.
class CdrError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Reads the fields of one serialized message in order.
class CdrReader {
 public:
  /// Throws CdrError when the encapsulation header is missing or not plain CDR.
  CdrReader(const std::uint8_t* data, size_t size);

  std::uint8_t U8();
  std::uint32_t U32();
  std::int32_t I32();
  double F64();
  std::string String();
  /// A uint8[] sequence: its bytes stay in the reader's buffer.
  const std::uint8_t* Bytes(size_t* count);
  /// Skips `n` doubles (a fixed float64[n] array).
  void SkipF64(size_t n);

 private:
  const std::uint8_t* Take(size_t bytes, size_t alignment);

  const std::uint8_t* data_;
  size_t size_;
  size_t offset_ = 4;  ///< next byte; alignment counts from 4 (the header's end)
  bool swap_ = false;  ///< big-endian payload
};

/// Writes little-endian CDR (ROS 2's default), the header included.
class CdrWriter {
 public:
  CdrWriter();
  void U8(std::uint8_t v);
  void U32(std::uint32_t v);
  void I32(std::int32_t v);
  void F64(double v);
  void String(const std::string& s);
  void Bytes(const std::uint8_t* data, size_t count);
  const std::vector<std::uint8_t>& bytes() const { return bytes_; }

 private:
  void Put(const void* v, size_t bytes);
  std::vector<std::uint8_t> bytes_;
};

}  // namespace vio::tools::ros2
