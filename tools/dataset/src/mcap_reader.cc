// MCAP files read record by record, chunks decompressed one at a time
// (uncompressed, zstd or lz4), so memory stays at one chunk whatever the
// file's size. The summary section is not needed and not read.
#include <cstdio>
#include <map>

#include <lz4frame.h>
#include <zlib.h>
#include <zstd.h>

#include "mcap_format.h"
#include "ros2_messages.h"
#include "ros2_storage.h"

namespace vio::tools::ros2 {
namespace {

/// A chunk that claims more than this uncompressed is corrupt, not allocated.
constexpr std::uint64_t kMaxChunkBytes = std::uint64_t{1} << 34;

class McapReader final : public MessageReader {
 public:
  McapReader(const std::string& path, const std::set<std::string>& topics) : path_(path), wanted_(topics) {
    file_ = std::fopen(path.c_str(), "rb");
    if (!file_) throw DatasetError(path + ": cannot open the MCAP file");
    std::fseek(file_, 0, SEEK_END);
    file_size_ = static_cast<std::uint64_t>(std::ftell(file_));
    std::fseek(file_, 0, SEEK_SET);
    std::uint8_t magic[8];
    if (std::fread(magic, 1, 8, file_) != 8 || std::memcmp(magic, mcap::kMagic, 8) != 0) {
      std::fclose(file_);
      throw DatasetError(path + ": not an MCAP file (no MCAP magic at its start)");
    }
    offset_ = 8;
  }
  ~McapReader() override { std::fclose(file_); }

  bool Next(Message* message) override {
    for (;;) {
      if (chunk_offset_ < chunk_size_) {
        if (InnerRecord(message)) return true;
        continue;
      }
      if (ended_) return false;
      if (OuterRecord(message)) return true;
    }
  }

  std::vector<Topic> Topics() const override {
    std::vector<Topic> topics;
    for (const auto& [id, topic] : channels_) topics.push_back(topic);
    return topics;
  }

 private:
  [[noreturn]] void Corrupt(const std::string& what, std::uint64_t at) const {
    throw DatasetError(path_ + ": " + what + " (at byte " + std::to_string(at) + " of " +
                       std::to_string(file_size_) + "; truncated or corrupt MCAP file)");
  }

  // One record of the data section; true when it was a message asked for.
  bool OuterRecord(Message* message) {
    std::uint8_t head[9];
    const std::uint64_t at = offset_;
    if (offset_ == file_size_) Corrupt("the file ends without the MCAP data end and footer", at);
    if (file_size_ - offset_ < 9 || std::fread(head, 1, 9, file_) != 9) Corrupt("a record header is cut off", at);
    mcap::Fields fields(head + 1, 8);
    const auto length = fields.Get<std::uint64_t>();
    offset_ += 9;
    if (length > file_size_ - offset_) {
      Corrupt("a record of " + std::to_string(length) + " bytes runs past the end of the file", at);
    }
    const std::uint8_t opcode = head[0];
    if (opcode == mcap::kDataEnd || opcode == mcap::kFooter) {
      ended_ = true;
      return false;
    }
    if (opcode != mcap::kChunk && opcode != mcap::kSchema && opcode != mcap::kChannel && opcode != mcap::kMessage) {
      std::fseek(file_, static_cast<long>(length), SEEK_CUR);
      offset_ += length;
      return false;
    }
    record_.resize(length);
    if (std::fread(record_.data(), 1, length, file_) != length) Corrupt("a record cannot be read", at);
    offset_ += length;
    if (opcode == mcap::kChunk) {
      OpenChunk(at);
      return false;
    }
    return Handle(opcode, record_.data(), length, at, message);
  }

  // One record inside the current chunk.
  bool InnerRecord(Message* message) {
    mcap::Fields fields(chunk_ + chunk_offset_, chunk_size_ - chunk_offset_);
    const auto opcode = fields.Get<std::uint8_t>();
    const auto length = fields.Get<std::uint64_t>();
    const std::uint8_t* content = fields.Take(length);
    if (!content) Corrupt("a record inside the chunk runs past the chunk's end", chunk_at_);
    chunk_offset_ += 9 + length;
    return Handle(opcode, content, length, chunk_at_, message);
  }

  bool Handle(std::uint8_t opcode, const std::uint8_t* content, std::uint64_t length, std::uint64_t at,
              Message* message) {
    mcap::Fields fields(content, length);
    if (opcode == mcap::kSchema) {
      const auto id = fields.Get<std::uint16_t>();
      schemas_[id] = CanonicalType(fields.String());
    } else if (opcode == mcap::kChannel) {
      const auto id = fields.Get<std::uint16_t>();
      const auto schema = fields.Get<std::uint16_t>();
      Topic& topic = channels_[id];
      topic.name = fields.String();
      topic.encoding = fields.String();
      topic.type = schemas_.count(schema) ? schemas_[schema] : "(no schema)";
    } else if (opcode == mcap::kMessage) {
      const auto channel = fields.Get<std::uint16_t>();
      fields.Get<std::uint32_t>();  // sequence
      message->log_time_ns = static_cast<std::int64_t>(fields.Get<std::uint64_t>());
      fields.Get<std::uint64_t>();  // publish time
      const auto it = channels_.find(channel);
      if (!fields.Ok() || it == channels_.end()) Corrupt("a message of an unknown channel", at);
      if (!wanted_.empty() && !wanted_.count(it->second.name)) return false;
      message->topic = &it->second;
      message->size = fields.Remaining();
      message->data = fields.Take(message->size);
      return true;
    }
    if (!fields.Ok()) Corrupt("a record shorter than its fields", at);
    return false;
  }

  void OpenChunk(std::uint64_t at) {
    mcap::Fields fields(record_.data(), record_.size());
    fields.Get<std::uint64_t>();  // message start time
    fields.Get<std::uint64_t>();  // message end time
    const auto uncompressed_size = fields.Get<std::uint64_t>();
    const auto crc = fields.Get<std::uint32_t>();
    const std::string compression = fields.String();
    const auto size = fields.Get<std::uint64_t>();
    const std::uint8_t* records = fields.Take(size);
    if (!records) Corrupt("a chunk shorter than its fields", at);
    if (uncompressed_size > kMaxChunkBytes) Corrupt("a chunk claims " + std::to_string(uncompressed_size) + " bytes", at);
    if (compression.empty()) {
      if (size != uncompressed_size) Corrupt("an uncompressed chunk's sizes differ", at);
      chunk_ = records;
    } else {
      Decompress(compression, records, size, uncompressed_size, at);
      chunk_ = inflated_.data();
    }
    chunk_size_ = uncompressed_size;
    chunk_offset_ = 0;
    chunk_at_ = at;
    if (crc != 0 && crc32_z(0L, chunk_, chunk_size_) != crc) Corrupt("a chunk's CRC does not match", at);
  }

  void Decompress(const std::string& compression, const std::uint8_t* data, size_t size, size_t uncompressed,
                  std::uint64_t at) {
    inflated_.resize(uncompressed);
    if (compression == "zstd") {
      const size_t n = ZSTD_decompress(inflated_.data(), uncompressed, data, size);
      if (ZSTD_isError(n) || n != uncompressed) Corrupt("a zstd chunk does not decompress", at);
    } else if (compression == "lz4") {
      LZ4F_dctx* context = nullptr;
      LZ4F_createDecompressionContext(&context, LZ4F_VERSION);
      size_t out = uncompressed, in = size;
      const size_t status = LZ4F_decompress(context, inflated_.data(), &out, data, &in, nullptr);
      LZ4F_freeDecompressionContext(context);
      if (LZ4F_isError(status) || status != 0 || out != uncompressed) Corrupt("an lz4 chunk does not decompress", at);
    } else {
      Corrupt("a chunk is compressed with '" + compression + "', which this reader does not know (zstd, lz4 or none)",
              at);
    }
  }

  std::string path_;
  std::set<std::string> wanted_;
  std::FILE* file_ = nullptr;
  std::uint64_t file_size_ = 0, offset_ = 0;
  bool ended_ = false;
  std::map<std::uint16_t, std::string> schemas_;
  std::map<std::uint16_t, Topic> channels_;
  std::vector<std::uint8_t> record_;    ///< the last record read from the file
  std::vector<std::uint8_t> inflated_;  ///< the current chunk, decompressed
  const std::uint8_t* chunk_ = nullptr;
  std::uint64_t chunk_size_ = 0, chunk_offset_ = 0, chunk_at_ = 0;
};

}  // namespace

std::unique_ptr<MessageReader> OpenMcap(const std::string& path, const std::set<std::string>& topics) {
  return std::make_unique<McapReader>(path, topics);
}

}  // namespace vio::tools::ros2
