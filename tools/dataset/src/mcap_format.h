#pragma once
// The MCAP container (mcap.dev/spec): the magic, record opcodes and
// little-endian field access shared by mcap_reader.cc and mcap_writer.cc.
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace vio::tools::ros2::mcap {

constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};

enum Opcode : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kDataEnd = 0x0F,
};

/// Little-endian fields of a record's content, bounds-checked: Ok() turns
/// false (and the values read zero) once a field runs past the end.
class Fields {
 public:
  Fields(const std::uint8_t* data, size_t size) : data_(data), size_(size) {}
  template <class T>
  T Get() {
    T v{};
    if (const std::uint8_t* p = Take(sizeof(T))) {
      for (size_t i = 0; i < sizeof(T); ++i) v = static_cast<T>(v | static_cast<T>(static_cast<T>(p[i]) << (8 * i)));
    }
    return v;
  }
  std::string String() {
    const auto length = Get<std::uint32_t>();
    const std::uint8_t* p = Take(length);
    return p ? std::string(reinterpret_cast<const char*>(p), length) : std::string();
  }
  /// `bytes` bytes (nullptr when past the end).
  const std::uint8_t* Take(std::uint64_t bytes) {
    if (!ok_ || bytes > size_ - offset_) {
      ok_ = false;
      return nullptr;
    }
    const std::uint8_t* p = data_ + offset_;
    offset_ += bytes;
    return p;
  }
  size_t Remaining() const { return size_ - offset_; }
  bool Ok() const { return ok_; }

 private:
  const std::uint8_t* data_;
  size_t size_;
  size_t offset_ = 0;
  bool ok_ = true;
};

/// Appends little-endian fields.
class Builder {
 public:
  template <class T>
  void Put(T v) {
    for (size_t i = 0; i < sizeof(T); ++i) bytes.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void String(const std::string& s) {
    Put(static_cast<std::uint32_t>(s.size()));
    bytes.insert(bytes.end(), s.begin(), s.end());
  }
  void Raw(const std::uint8_t* data, size_t size) { bytes.insert(bytes.end(), data, data + size); }
  std::vector<std::uint8_t> bytes;
};

}  // namespace vio::tools::ros2::mcap
