// An ASL folder written as a ROS 2 recording (`vio convert`): the IMU, the
// ground truth and both cameras' images merged in stamp order, images read
// one at a time with the decoder an ASL run uses.
#include <filesystem>
#include <limits>

#include "ros2_messages.h"
#include "ros2_storage.h"
#include "vio/dataset/image_file.h"
#include "vio/dataset/ros2_dataset.h"

namespace vio::tools {
namespace {

namespace fs = std::filesystem;

// The topics written, in the order of ros2::Topic indices.
enum Stream { kImu, kCam0, kCam1, kGroundTruth };

struct Output {
  std::string file;  ///< the storage file
  std::string folder;  ///< the bag folder (empty: a lone .mcap/.db3 file)
  bool mcap = true;
};

Output OutputOf(const std::string& path, const Ros2WriteOptions& options) {
  const fs::path p(path);
  if (p.extension() == ".mcap" || p.extension() == ".db3") return {path, "", p.extension() == ".mcap"};
  if (options.storage != "mcap" && options.storage != "sqlite3") {
    throw DatasetError(path + ": unknown ROS 2 storage '" + options.storage + "' (mcap or sqlite3)");
  }
  const bool mcap = options.storage == "mcap";
  fs::create_directories(p);
  const std::string name = p.filename().empty() ? p.parent_path().filename().string() : p.filename().string();
  return {(p / (name + (mcap ? "_0.mcap" : "_0.db3"))).string(), path, mcap};
}

class MergedWriter {
 public:
  MergedWriter(const EurocDataset& dataset, ros2::MessageWriter& out) : dataset_(dataset), out_(out) {}

  // Writes every message; returns the count per stream.
  std::vector<size_t> Run() {
    const size_t sizes[4] = {dataset_.imu.size(), dataset_.frames[0].size(), dataset_.frames[1].size(),
                             dataset_.groundtruth.size()};
    for (;;) {
      int stream = -1;
      Timestamp best = std::numeric_limits<Timestamp>::max();
      for (int s = 0; s < 4; ++s) {
        if (next_[s] < sizes[s] && Stamp(s, next_[s]) < best) best = Stamp(s, next_[s]), stream = s;
      }
      if (stream < 0) break;
      Write(stream, next_[stream]++);
    }
    return {next_[0], next_[1], next_[2], next_[3]};
  }

 private:
  Timestamp Stamp(int stream, size_t i) const {
    if (stream == kImu) return dataset_.imu[i].t_ns;
    if (stream == kGroundTruth) return dataset_.groundtruth[i].t_ns;
    return dataset_.frames[stream - kCam0][i].t_ns;
  }

  void Write(int stream, size_t i) {
    const Timestamp t = Stamp(stream, i);
    if (stream == kImu) return out_.Write(kImu, t, ros2::EncodeImu(dataset_.imu[i], "imu0"));
    if (stream == kGroundTruth) return out_.Write(kGroundTruth, t, ros2::EncodePoseStamped(dataset_.groundtruth[i], "world"));
    const int camera = stream - kCam0;
    const std::string file =
        dataset_.root + "/mav0/cam" + std::to_string(camera) + "/data/" + dataset_.frames[camera][i].filename;
    const cv::Mat grey = ReadGreyImage(file);
    if (grey.empty()) throw DatasetError(file + ": cannot read the image");
    out_.Write(static_cast<size_t>(stream), t, ros2::EncodeImage(grey, t, "cam" + std::to_string(camera)));
  }

  const EurocDataset& dataset_;
  ros2::MessageWriter& out_;
  size_t next_[4] = {0, 0, 0, 0};
};

}  // namespace

void WriteRos2Bag(const EurocDataset& dataset, const std::string& path, const BagTopics& topics,
                  const Ros2WriteOptions& options) {
  if (options.compression != "zstd" && options.compression != "lz4" && options.compression != "none") {
    throw DatasetError(path + ": unknown MCAP compression '" + options.compression + "' (zstd, lz4 or none)");
  }
  const Output output = OutputOf(path, options);
  std::vector<ros2::Topic> list = {{topics.imu_topic, ros2::kImuType},
                                   {topics.cam0_topic, ros2::kImageType},
                                   {topics.cam1_topic, ros2::kImageType}};
  EurocDataset data = dataset;
  if (topics.groundtruth_topic.empty()) data.groundtruth.clear();
  if (!data.groundtruth.empty()) list.push_back({topics.groundtruth_topic, ros2::kPoseStampedType});
  std::unique_ptr<ros2::MessageWriter> writer =
      output.mcap ? ros2::CreateMcap(output.file, list, options.compression == "none" ? "" : options.compression)
                  : ros2::CreateSqlite(output.file, list);
  std::vector<size_t> counts = MergedWriter(data, *writer).Run();
  writer->Close();
  if (output.folder.empty()) return;
  counts.resize(list.size());
  ros2::BagSummary summary{fs::path(output.file).filename().string(), output.mcap, list, counts, 0, 0};
  if (!data.imu.empty()) summary.start_ns = data.imu.front().t_ns, summary.end_ns = data.imu.back().t_ns;
  for (const std::vector<CameraFrame>& frames : data.frames) {
    if (frames.empty()) continue;
    summary.start_ns = std::min(summary.start_ns, frames.front().t_ns);
    summary.end_ns = std::max(summary.end_ns, frames.back().t_ns);
  }
  ros2::WriteMetadataYaml(output.folder, summary);
}

}  // namespace vio::tools
