// Which files a ROS 2 recording is (ResolveBag), reading them in order as one
// stream (BagReader), and a bag folder's metadata.yaml.
#include "ros2_storage.h"

#include <filesystem>
#include <fstream>

#include <yaml-cpp/yaml.h>

namespace vio::tools::ros2 {
namespace {

namespace fs = std::filesystem;

bool HasExtension(const std::string& path, const char* extension) {
  return fs::path(path).extension() == extension;
}

// A file the metadata names: relative to the folder (older rosbag2 releases
// wrote the folder's own name in front).
std::string BagFile(const fs::path& folder, const std::string& relative) {
  for (const fs::path& candidate : {folder / relative, folder.parent_path() / relative,
                                    folder / fs::path(relative).filename()}) {
    if (fs::is_regular_file(candidate)) return candidate.string();
  }
  throw DatasetError((folder / "metadata.yaml").string() + ": its file " + relative + " is not in " + folder.string());
}

BagFiles ResolveFolder(const std::string& path) {
  const fs::path folder(path);
  const std::string metadata = (folder / "metadata.yaml").string();
  if (!fs::is_regular_file(metadata)) throw DatasetError(path + ": a ROS 2 bag folder needs its metadata.yaml");
  BagFiles bag;
  bag.path = path;
  try {
    const YAML::Node info = YAML::LoadFile(metadata)["rosbag2_bagfile_information"];
    if (!info) throw DatasetError(metadata + ": no rosbag2_bagfile_information: not a rosbag2 metadata file");
    const std::string storage = info["storage_identifier"].as<std::string>("");
    if (storage != "sqlite3" && storage != "mcap") {
      throw DatasetError(metadata + ": storage_identifier '" + storage + "' (this reader knows sqlite3 and mcap)");
    }
    bag.mcap = storage == "mcap";
    const std::string compression = info["compression_format"].as<std::string>("");
    if (!compression.empty()) {
      throw DatasetError(metadata + ": the bag is compressed with " + compression + " (mode " +
                         info["compression_mode"].as<std::string>("") +
                         "), which this reader cannot read: record without --compression-mode, or use MCAP's "
                         "own chunk compression");
    }
    for (const YAML::Node& file : info["relative_file_paths"]) bag.files.push_back(BagFile(folder, file.as<std::string>()));
  } catch (const YAML::Exception& e) {
    throw DatasetError(metadata + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  if (bag.files.empty()) throw DatasetError(metadata + ": relative_file_paths lists no file");
  return bag;
}

}  // namespace

BagFiles ResolveBag(const std::string& path) {
  if (fs::is_directory(path)) return ResolveFolder(path);
  if (!fs::is_regular_file(path)) throw DatasetError(path + ": no such file or folder");
  if (!HasExtension(path, ".mcap") && !HasExtension(path, ".db3")) {
    throw DatasetError(path + ": not a ROS 2 recording (FILE.mcap, FILE.db3 or a bag folder with metadata.yaml)");
  }
  return BagFiles{path, {path}, HasExtension(path, ".mcap")};
}

BagReader::BagReader(BagFiles bag, std::set<std::string> topics) : bag_(std::move(bag)), topics_(std::move(topics)) {
  reader_ = bag_.mcap ? OpenMcap(bag_.files[0], topics_) : OpenSqlite(bag_.files[0], topics_);
}

bool BagReader::Next(Message* message) {
  while (!reader_->Next(message)) {
    if (index_ + 1 == bag_.files.size()) return false;
    for (Topic& topic : reader_->Topics()) seen_.push_back(std::move(topic));
    ++index_;
    reader_ = bag_.mcap ? OpenMcap(bag_.files[index_], topics_) : OpenSqlite(bag_.files[index_], topics_);
  }
  return true;
}

MessagePlace BagReader::Place() const {
  MessagePlace place = reader_->Place();
  place.file = index_;
  return place;
}

std::vector<Topic> BagReader::Topics() const {
  std::vector<Topic> all = seen_;
  for (Topic& topic : reader_->Topics()) all.push_back(std::move(topic));
  std::set<std::string> names;
  std::vector<Topic> topics;
  for (Topic& topic : all) {
    if (names.insert(topic.name).second) topics.push_back(std::move(topic));
  }
  return topics;
}

void WriteMetadataYaml(const std::string& folder, const BagSummary& summary) {
  size_t total = 0;
  for (size_t n : summary.counts) total += n;
  const std::string duration = std::to_string(summary.end_ns - summary.start_ns);
  const std::string start = std::to_string(summary.start_ns);
  std::ofstream out(folder + "/metadata.yaml");
  out << "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: "
      << (summary.mcap ? "mcap" : "sqlite3") << "\n  duration:\n    nanoseconds: " << duration
      << "\n  starting_time:\n    nanoseconds_since_epoch: " << start << "\n  message_count: " << total
      << "\n  topics_with_message_count:\n";
  for (size_t i = 0; i < summary.topics.size(); ++i) {
    out << "    - topic_metadata:\n        name: " << summary.topics[i].name
        << "\n        type: " << summary.topics[i].type
        << "\n        serialization_format: cdr\n        offered_qos_profiles: \"\"\n      message_count: "
        << summary.counts[i] << "\n";
  }
  out << "  compression_format: \"\"\n  compression_mode: \"\"\n  relative_file_paths:\n    - " << summary.file
      << "\n  files:\n    - path: " << summary.file << "\n      starting_time:\n        nanoseconds_since_epoch: "
      << start << "\n      duration:\n        nanoseconds: " << duration << "\n      message_count: " << total << "\n";
  if (!out) throw DatasetError(folder + "/metadata.yaml: cannot write");
}

}  // namespace vio::tools::ros2
