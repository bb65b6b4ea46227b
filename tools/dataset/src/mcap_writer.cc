// MCAP files as `vio convert` writes them: the header, one schema (ros2msg)
// and channel (cdr) per topic, the messages in chunks of about kChunkBytes
// (zstd, lz4 or uncompressed), the data end and the footer. No summary
// section: readers scan the file (the format allows it).
#include <cstdio>
#include <fstream>

#include <libdeflate.h>
#include <lz4frame.h>
#include <zstd.h>

#include "mcap_format.h"
#include "ros2_messages.h"
#include "ros2_storage.h"

namespace vio::tools::ros2 {
namespace {

constexpr size_t kChunkBytes = 4 << 20;

class McapWriter final : public MessageWriter {
 public:
  McapWriter(const std::string& path, const std::vector<Topic>& topics, const std::string& compression)
      : path_(path), compression_(compression), out_(path, std::ios::binary) {
    if (compression != "" && compression != "zstd" && compression != "lz4") {
      throw DatasetError(path + ": unknown MCAP chunk compression '" + compression + "' (zstd, lz4 or none)");
    }
    if (!out_) throw DatasetError(path + ": cannot write the MCAP file");
    out_.write(reinterpret_cast<const char*>(mcap::kMagic), 8);
    mcap::Builder header;
    header.String("ros2");
    header.String("vio");
    Record(mcap::kHeader, header.bytes);
    for (size_t i = 0; i < topics.size(); ++i) {
      const auto id = static_cast<std::uint16_t>(i + 1);
      mcap::Builder schema;
      schema.Put(id);
      schema.String(topics[i].type);
      schema.String("ros2msg");
      schema.String(MessageDefinition(topics[i].type));
      Record(mcap::kSchema, schema.bytes);
      mcap::Builder channel;
      channel.Put(id);
      channel.Put(id);
      channel.String(topics[i].name);
      channel.String("cdr");
      channel.Put(std::uint32_t{0});  // no metadata
      Record(mcap::kChannel, channel.bytes);
    }
    sequence_.assign(topics.size(), 0);
  }

  void Write(size_t topic, std::int64_t log_time_ns, const std::vector<std::uint8_t>& data) override {
    mcap::Builder message;
    message.Put(static_cast<std::uint16_t>(topic + 1));
    message.Put(sequence_[topic]++);
    message.Put(static_cast<std::uint64_t>(log_time_ns));
    message.Put(static_cast<std::uint64_t>(log_time_ns));
    message.Raw(data.data(), data.size());
    if (chunk_.bytes.empty()) start_ns_ = end_ns_ = log_time_ns;
    chunk_.Put(static_cast<std::uint8_t>(mcap::kMessage));
    chunk_.Put(static_cast<std::uint64_t>(message.bytes.size()));
    chunk_.Raw(message.bytes.data(), message.bytes.size());
    start_ns_ = std::min(start_ns_, log_time_ns);
    end_ns_ = std::max(end_ns_, log_time_ns);
    if (chunk_.bytes.size() >= kChunkBytes) Flush();
  }

  void Close() override {
    Flush();
    Record(mcap::kDataEnd, std::vector<std::uint8_t>(4, 0));  // data section CRC 0: not computed
    mcap::Builder footer;
    footer.Put(std::uint64_t{0});  // no summary section
    footer.Put(std::uint64_t{0});
    footer.Put(std::uint32_t{0});
    Record(mcap::kFooter, footer.bytes);
    out_.write(reinterpret_cast<const char*>(mcap::kMagic), 8);
    out_.close();
    if (!out_) throw DatasetError(path_ + ": cannot write the MCAP file (disk full?)");
  }

 private:
  void Record(std::uint8_t opcode, const std::vector<std::uint8_t>& content) {
    mcap::Builder head;
    head.Put(opcode);
    head.Put(static_cast<std::uint64_t>(content.size()));
    out_.write(reinterpret_cast<const char*>(head.bytes.data()), static_cast<std::streamsize>(head.bytes.size()));
    out_.write(reinterpret_cast<const char*>(content.data()), static_cast<std::streamsize>(content.size()));
  }

  std::vector<std::uint8_t> Compress(const std::vector<std::uint8_t>& raw) const {
    std::vector<std::uint8_t> packed;
    if (compression_ == "zstd") {
      packed.resize(ZSTD_compressBound(raw.size()));
      const size_t n = ZSTD_compress(packed.data(), packed.size(), raw.data(), raw.size(), ZSTD_CLEVEL_DEFAULT);
      if (ZSTD_isError(n)) throw DatasetError(path_ + ": zstd compression failed");
      packed.resize(n);
    } else {
      packed.resize(LZ4F_compressFrameBound(raw.size(), nullptr));
      const size_t n = LZ4F_compressFrame(packed.data(), packed.size(), raw.data(), raw.size(), nullptr);
      if (LZ4F_isError(n)) throw DatasetError(path_ + ": lz4 compression failed");
      packed.resize(n);
    }
    return packed;
  }

  void Flush() {
    if (chunk_.bytes.empty()) return;
    const std::vector<std::uint8_t>& raw = chunk_.bytes;
    const std::vector<std::uint8_t> packed = compression_.empty() ? std::vector<std::uint8_t>() : Compress(raw);
    const std::vector<std::uint8_t>& records = compression_.empty() ? raw : packed;
    mcap::Builder chunk;
    chunk.Put(static_cast<std::uint64_t>(start_ns_));
    chunk.Put(static_cast<std::uint64_t>(end_ns_));
    chunk.Put(static_cast<std::uint64_t>(raw.size()));
    chunk.Put(static_cast<std::uint32_t>(libdeflate_crc32(0, raw.data(), raw.size())));
    chunk.String(compression_);
    chunk.Put(static_cast<std::uint64_t>(records.size()));
    chunk.Raw(records.data(), records.size());
    Record(mcap::kChunk, chunk.bytes);
    chunk_.bytes.clear();
  }

  std::string path_;
  std::string compression_;
  std::ofstream out_;
  std::vector<std::uint32_t> sequence_;
  mcap::Builder chunk_;  ///< the records of the open chunk
  std::int64_t start_ns_ = 0, end_ns_ = 0;
};

}  // namespace

std::unique_ptr<MessageWriter> CreateMcap(const std::string& path, const std::vector<Topic>& topics,
                                          const std::string& compression) {
  return std::make_unique<McapWriter>(path, topics, compression);
}

}  // namespace vio::tools::ros2
