// MCAP files read record by record, chunks decompressed one at a time
// (uncompressed, zstd or lz4), so memory stays at one chunk whatever the
// file's size; and read again message by message at the places the first
// read found (McapFetcher: the last two chunks kept). The summary section is
// not needed and not read.
#include <cstdio>
#include <map>

#include <libdeflate.h>
#include <lz4frame.h>
#include <zstd.h>

#include "mcap_format.h"
#include "ros2_messages.h"
#include "ros2_storage.h"

namespace vio::tools::ros2 {
namespace {

/// A chunk that claims more than this uncompressed is corrupt, not allocated.
constexpr std::uint64_t kMaxChunkBytes = std::uint64_t{1} << 34;

/// The records of a chunk, decompressed.
struct ChunkRecords {
  const std::uint8_t* data = nullptr;
  std::uint64_t size = 0;
};

// An open MCAP file: its errors, and its chunks decompressed with one reused
// zstd context.
class McapFile {
 public:
  explicit McapFile(const std::string& path) : path_(path) {
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
  }
  ~McapFile() {
    std::fclose(file_);
    ZSTD_freeDCtx(zstd_);
  }
  McapFile(const McapFile&) = delete;
  McapFile& operator=(const McapFile&) = delete;

 protected:
  [[noreturn]] void Corrupt(const std::string& what, std::uint64_t at) const {
    throw DatasetError(path_ + ": " + what + " (at byte " + std::to_string(at) + " of " +
                       std::to_string(file_size_) + "; truncated or corrupt MCAP file)");
  }

  /// The records of the chunk record content `record` (at file offset `at`),
  /// decompressed into `inflated` when compressed; the CRC checked when asked.
  ChunkRecords OpenChunk(const std::vector<std::uint8_t>& record, std::uint64_t at, bool check_crc,
                         std::vector<std::uint8_t>* inflated) {
    mcap::Fields fields(record.data(), record.size());
    fields.Get<std::uint64_t>();  // message start time
    fields.Get<std::uint64_t>();  // message end time
    const auto uncompressed_size = fields.Get<std::uint64_t>();
    const auto crc = fields.Get<std::uint32_t>();
    const std::string compression = fields.String();
    const auto size = fields.Get<std::uint64_t>();
    const std::uint8_t* records = fields.Take(size);
    if (!records) Corrupt("a chunk shorter than its fields", at);
    if (uncompressed_size > kMaxChunkBytes) Corrupt("a chunk claims " + std::to_string(uncompressed_size) + " bytes", at);
    ChunkRecords chunk{records, uncompressed_size};
    if (compression.empty()) {
      if (size != uncompressed_size) Corrupt("an uncompressed chunk's sizes differ", at);
    } else {
      Decompress(compression, records, size, uncompressed_size, at, inflated);
      chunk.data = inflated->data();
    }
    if (check_crc && crc != 0 && libdeflate_crc32(0, chunk.data, chunk.size) != crc) {
      Corrupt("a chunk's CRC does not match", at);
    }
    return chunk;
  }

  std::string path_;
  std::FILE* file_ = nullptr;
  std::uint64_t file_size_ = 0;

 private:
  void Decompress(const std::string& compression, const std::uint8_t* data, size_t size, size_t uncompressed,
                  std::uint64_t at, std::vector<std::uint8_t>* inflated) {
    inflated->resize(uncompressed);
    if (compression == "zstd") {
      if (!zstd_) zstd_ = ZSTD_createDCtx();
      const size_t n = ZSTD_decompressDCtx(zstd_, inflated->data(), uncompressed, data, size);
      if (ZSTD_isError(n) || n != uncompressed) Corrupt("a zstd chunk does not decompress", at);
    } else if (compression == "lz4") {
      LZ4F_dctx* context = nullptr;
      LZ4F_createDecompressionContext(&context, LZ4F_VERSION);
      size_t out = uncompressed, in = size;
      const size_t status = LZ4F_decompress(context, inflated->data(), &out, data, &in, nullptr);
      LZ4F_freeDecompressionContext(context);
      if (LZ4F_isError(status) || status != 0 || out != uncompressed) Corrupt("an lz4 chunk does not decompress", at);
    } else {
      Corrupt("a chunk is compressed with '" + compression + "', which this reader does not know (zstd, lz4 or none)",
              at);
    }
  }

  ZSTD_DCtx* zstd_ = nullptr;
};

class McapReader final : public MessageReader, McapFile {
 public:
  McapReader(const std::string& path, const std::set<std::string>& topics) : McapFile(path), wanted_(topics) {}

  bool Next(Message* message) override {
    for (;;) {
      if (chunk_offset_ < chunk_.size) {
        if (InnerRecord(message)) return true;
        continue;
      }
      if (ended_) return false;
      if (OuterRecord(message)) return true;
    }
  }

  MessagePlace Place() const override { return place_; }

  std::vector<Topic> Topics() const override {
    std::vector<Topic> topics;
    for (const auto& [id, topic] : channels_) topics.push_back(topic);
    return topics;
  }

 private:
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
      chunk_ = OpenChunk(record_, at, /*check_crc=*/true, &inflated_);
      chunk_offset_ = 0;
      chunk_at_ = at;
      return false;
    }
    place_ = MessagePlace{0, at, MessagePlace::kNoChunk};
    return Handle(opcode, record_.data(), length, at, message);
  }

  // One record inside the current chunk.
  bool InnerRecord(Message* message) {
    mcap::Fields fields(chunk_.data + chunk_offset_, chunk_.size - chunk_offset_);
    const auto opcode = fields.Get<std::uint8_t>();
    const auto length = fields.Get<std::uint64_t>();
    const std::uint8_t* content = fields.Take(length);
    if (!content) Corrupt("a record inside the chunk runs past the chunk's end", chunk_at_);
    place_ = MessagePlace{0, chunk_at_, chunk_offset_};
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

  std::set<std::string> wanted_;
  std::uint64_t offset_ = 8;  ///< after the magic
  bool ended_ = false;
  std::map<std::uint16_t, std::string> schemas_;
  std::map<std::uint16_t, Topic> channels_;
  std::vector<std::uint8_t> record_;    ///< the last record read from the file
  std::vector<std::uint8_t> inflated_;  ///< the current chunk, decompressed
  ChunkRecords chunk_;
  std::uint64_t chunk_offset_ = 0, chunk_at_ = 0;
  MessagePlace place_;  ///< of the last message
};

// Messages read at their places; a chunk is decompressed once while it is
// one of the last two used (a stereo pair's two images share a chunk).
class McapFetcher final : public MessageFetcher, McapFile {
 public:
  explicit McapFetcher(const std::string& path) : McapFile(path) {}

  void Fetch(const MessagePlace& place, Message* message) override {
    if (place.inner == MessagePlace::kNoChunk) {
      ReadRecord(place.record, mcap::kMessage, &single_);
      Parse(single_.data(), single_.size(), place.record, message);
      return;
    }
    const Slot& slot = Chunk(place.record);
    if (place.inner >= slot.chunk.size) Corrupt("a message place past its chunk's end", place.record);
    mcap::Fields fields(slot.chunk.data + place.inner, slot.chunk.size - place.inner);
    const auto opcode = fields.Get<std::uint8_t>();
    const auto length = fields.Get<std::uint64_t>();
    const std::uint8_t* content = fields.Take(length);
    if (!content || opcode != mcap::kMessage) Corrupt("no message record at its place in the chunk", place.record);
    Parse(content, length, place.record, message);
  }

 private:
  struct Slot {
    std::uint64_t at = MessagePlace::kNoChunk;
    std::vector<std::uint8_t> records;  ///< the chunk's records, decompressed
    ChunkRecords chunk;
  };

  // The chunk record at `at`, decompressed (reusing the least recent slot).
  const Slot& Chunk(std::uint64_t at) {
    for (Slot& slot : slots_) {
      if (slot.at == at) {
        recent_ = &slot - slots_;
        return slot;
      }
    }
    recent_ = 1 - recent_;
    Slot& slot = slots_[recent_];
    slot.at = MessagePlace::kNoChunk;
    ReadRecord(at, mcap::kChunk, &record_);
    slot.chunk = OpenChunk(record_, at, /*check_crc=*/false, &slot.records);
    // An uncompressed chunk's records are inside the record: the slot keeps
    // that buffer (a swap moves no bytes; the pointer stays valid).
    if (slot.chunk.data != slot.records.data()) slot.records.swap(record_);
    slot.at = at;
    return slot;
  }

  // The content of the record at `at`, which must have opcode `opcode`.
  void ReadRecord(std::uint64_t at, std::uint8_t opcode, std::vector<std::uint8_t>* content) {
    std::uint8_t head[9];
    if (at > file_size_ || file_size_ - at < 9 || std::fseek(file_, static_cast<long>(at), SEEK_SET) != 0 ||
        std::fread(head, 1, 9, file_) != 9) {
      Corrupt("a record header is cut off", at);
    }
    mcap::Fields fields(head + 1, 8);
    const auto length = fields.Get<std::uint64_t>();
    if (head[0] != opcode) Corrupt("not the record found there before", at);
    if (length > file_size_ - at - 9) Corrupt("a record of " + std::to_string(length) + " bytes runs past the end of the file", at);
    content->resize(length);
    if (std::fread(content->data(), 1, length, file_) != length) Corrupt("a record cannot be read", at);
  }

  void Parse(const std::uint8_t* content, std::uint64_t length, std::uint64_t at, Message* message) const {
    mcap::Fields fields(content, length);
    fields.Get<std::uint16_t>();  // channel
    fields.Get<std::uint32_t>();  // sequence
    message->log_time_ns = static_cast<std::int64_t>(fields.Get<std::uint64_t>());
    fields.Get<std::uint64_t>();  // publish time
    if (!fields.Ok()) Corrupt("a record shorter than its fields", at);
    message->size = fields.Remaining();
    message->data = fields.Take(message->size);
  }

  Slot slots_[2];
  std::ptrdiff_t recent_ = 0;       ///< the slot used last
  std::vector<std::uint8_t> record_;  ///< the last chunk record read, compressed
  std::vector<std::uint8_t> single_;  ///< a message record outside chunks
};

}  // namespace

std::unique_ptr<MessageReader> OpenMcap(const std::string& path, const std::set<std::string>& topics) {
  return std::make_unique<McapReader>(path, topics);
}

std::unique_ptr<MessageFetcher> OpenMcapFetcher(const std::string& path) {
  return std::make_unique<McapFetcher>(path);
}

}  // namespace vio::tools::ros2
