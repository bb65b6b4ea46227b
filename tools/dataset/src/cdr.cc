#include "cdr.h"

#include <cstring>

namespace vio::tools::ros2 {
namespace {

bool HostIsLittleEndian() {
  const std::uint16_t one = 1;
  std::uint8_t first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

template <class T>
T Load(const std::uint8_t* p, bool swap) {
  std::uint8_t bytes[sizeof(T)];
  std::memcpy(bytes, p, sizeof(T));
  if (swap) {
    for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
  }
  T v;
  std::memcpy(&v, bytes, sizeof(T));
  return v;
}

}  // namespace

CdrReader::CdrReader(const std::uint8_t* data, size_t size) : data_(data), size_(size) {
  if (size < 4) throw CdrError("CDR message of " + std::to_string(size) + " bytes: no encapsulation header");
  if (data[0] != 0 || data[1] > 1) {
    throw CdrError("CDR encapsulation " + std::to_string(data[0]) + "," + std::to_string(data[1]) +
                   " is not plain CDR (0,0 or 0,1)");
  }
  const bool little = data[1] == 1;
  swap_ = little != HostIsLittleEndian();
}

const std::uint8_t* CdrReader::Take(size_t bytes, size_t alignment) {
  const size_t aligned = 4 + (offset_ - 4 + alignment - 1) / alignment * alignment;
  if (aligned > size_ || bytes > size_ - aligned) {
    throw CdrError("CDR message of " + std::to_string(size_) + " bytes ends before byte " +
                   std::to_string(aligned + bytes) + " (truncated or not this message type)");
  }
  offset_ = aligned + bytes;
  return data_ + aligned;
}

std::uint8_t CdrReader::U8() { return *Take(1, 1); }
std::uint32_t CdrReader::U32() { return Load<std::uint32_t>(Take(4, 4), swap_); }
std::int32_t CdrReader::I32() { return Load<std::int32_t>(Take(4, 4), swap_); }
double CdrReader::F64() { return Load<double>(Take(8, 8), swap_); }
void CdrReader::SkipF64(size_t n) {
  if (n > 0) Take(8 * n, 8);
}

std::string CdrReader::String() {
  const std::uint32_t length = U32();
  if (length == 0) return {};  // some writers leave out the NUL of an empty string
  const std::uint8_t* p = Take(length, 1);
  return std::string(reinterpret_cast<const char*>(p), p[length - 1] == 0 ? length - 1 : length);
}

const std::uint8_t* CdrReader::Bytes(size_t* count) {
  *count = U32();
  return Take(*count, 1);
}

CdrWriter::CdrWriter() : bytes_{0, 1, 0, 0} {}

void CdrWriter::Put(const void* v, size_t bytes) {
  while ((bytes_.size() - 4) % bytes != 0) bytes_.push_back(0);
  const auto* p = static_cast<const std::uint8_t*>(v);
  if (HostIsLittleEndian()) {
    bytes_.insert(bytes_.end(), p, p + bytes);
  } else {
    for (size_t i = bytes; i > 0; --i) bytes_.push_back(p[i - 1]);
  }
}

void CdrWriter::U8(std::uint8_t v) { bytes_.push_back(v); }
void CdrWriter::U32(std::uint32_t v) { Put(&v, 4); }
void CdrWriter::I32(std::int32_t v) { Put(&v, 4); }
void CdrWriter::F64(double v) { Put(&v, 8); }

void CdrWriter::String(const std::string& s) {
  U32(static_cast<std::uint32_t>(s.size() + 1));
  bytes_.insert(bytes_.end(), s.begin(), s.end());
  bytes_.push_back(0);
}

void CdrWriter::Bytes(const std::uint8_t* data, size_t count) {
  U32(static_cast<std::uint32_t>(count));
  bytes_.insert(bytes_.end(), data, data + count);
}

}  // namespace vio::tools::ros2
