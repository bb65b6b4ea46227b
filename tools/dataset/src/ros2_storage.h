#pragma once
// The storage of ROS 2 recordings without ROS: MCAP files (mcap_reader.cc,
// mcap_writer.cc) and rosbag2 sqlite3 files (rosbag2_sqlite.cc), each read as
// its messages in file order, and bag folders (metadata.yaml naming one or
// several such files); messages read again at the places a first read found
// (MessageFetcher). Errors are DatasetErrors naming the file.
#include <cstdint>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "vio/dataset/euroc_dataset.h"

namespace vio::tools::ros2 {

struct Topic {
  std::string name;
  std::string type;              ///< pkg/msg/Name
  std::string encoding = "cdr";  ///< the serialization of its messages
};

/// One message; `topic` and the bytes stay valid until the next Next().
struct Message {
  const Topic* topic = nullptr;
  std::int64_t log_time_ns = 0;
  const std::uint8_t* data = nullptr;
  size_t size = 0;
};

/// Where a message lives in a recording, for reading it again: MCAP, the file
/// offset of its chunk record and its record's offset inside the
/// decompressed chunk (outside chunks: its record's file offset, inner
/// kNoChunk); sqlite3, its row id (record).
struct MessagePlace {
  static constexpr std::uint64_t kNoChunk = ~std::uint64_t{0};
  size_t file = 0;  ///< index into BagFiles::files
  std::uint64_t record = 0;
  std::uint64_t inner = kNoChunk;
};

/// The messages of one storage file, in file order.
class MessageReader {
 public:
  virtual ~MessageReader() = default;
  /// The next message of one of the topics asked for; false after the last.
  virtual bool Next(Message* message) = 0;
  /// Where the last message returned lives (file 0).
  virtual MessagePlace Place() const = 0;
  /// The file's topics (MCAP: those whose channel was read so far).
  virtual std::vector<Topic> Topics() const = 0;
};

/// `topics`: the topic names to return messages of (empty: all).
std::unique_ptr<MessageReader> OpenMcap(const std::string& path, const std::set<std::string>& topics);
std::unique_ptr<MessageReader> OpenSqlite(const std::string& path, const std::set<std::string>& topics);

/// Messages of one storage file read again at places a MessageReader gave
/// (MCAP chunk CRCs are not checked again: the reader did).
class MessageFetcher {
 public:
  virtual ~MessageFetcher() = default;
  /// The message at `place` (its bytes and log time; `topic` is left as is),
  /// valid until the next Fetch.
  virtual void Fetch(const MessagePlace& place, Message* message) = 0;
};

std::unique_ptr<MessageFetcher> OpenMcapFetcher(const std::string& path);
std::unique_ptr<MessageFetcher> OpenSqliteFetcher(const std::string& path);

/// Writes one storage file; topics are indices into the list given at creation.
class MessageWriter {
 public:
  virtual ~MessageWriter() = default;
  virtual void Write(size_t topic, std::int64_t log_time_ns, const std::vector<std::uint8_t>& data) = 0;
  /// Finishes the file (an MCAP's footer, the sqlite transaction).
  virtual void Close() = 0;
};

/// `compression`: "zstd", "lz4" or "" (none) for the MCAP chunks.
std::unique_ptr<MessageWriter> CreateMcap(const std::string& path, const std::vector<Topic>& topics,
                                          const std::string& compression);
std::unique_ptr<MessageWriter> CreateSqlite(const std::string& path, const std::vector<Topic>& topics);

/// A recording's storage files in order.
struct BagFiles {
  std::string path;                ///< as the user named it
  std::vector<std::string> files;  ///< the .mcap or .db3 files
  bool mcap = true;                ///< else sqlite3
};

/// A .mcap or .db3 file, or a bag folder with metadata.yaml. Throws
/// DatasetError on anything else, or on file-compressed bags.
BagFiles ResolveBag(const std::string& path);

/// Every file of a bag in order, as one stream.
class BagReader {
 public:
  BagReader(BagFiles bag, std::set<std::string> topics);
  bool Next(Message* message);
  /// The file of the last message.
  const std::string& file() const { return bag_.files[index_]; }
  /// Where the last message lives.
  MessagePlace Place() const;
  /// Every topic of the files opened so far, once each.
  std::vector<Topic> Topics() const;

 private:
  BagFiles bag_;
  std::set<std::string> topics_;
  size_t index_ = 0;
  std::unique_ptr<MessageReader> reader_;
  std::vector<Topic> seen_;
};

}  // namespace vio::tools::ros2

namespace vio::tools::ros2 {

/// What a bag folder's metadata.yaml says of its one storage file.
struct BagSummary {
  std::string file;                  ///< its name inside the folder
  bool mcap = true;                  ///< else sqlite3
  std::vector<Topic> topics;
  std::vector<size_t> counts;        ///< messages per topic
  std::int64_t start_ns = 0, end_ns = 0;
};

/// Writes <folder>/metadata.yaml (rosbag2 metadata version 5).
void WriteMetadataYaml(const std::string& folder, const BagSummary& summary);

}  // namespace vio::tools::ros2
