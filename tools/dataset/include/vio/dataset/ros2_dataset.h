#pragma once
// ROS 2 recordings without ROS: MCAP files (chunks uncompressed, zstd or
// lz4), rosbag2 sqlite3 files (.db3) and bag folders (metadata.yaml naming
// one or several .db3 or .mcap files), read by this project's own small
// readers over libzstd, liblz4 and libsqlite3. Topics and defaults are the
// ROS 1 path's (BagTopics); stamps are the header stamps. Images are
// sensor_msgs/msg/Image (mono8, 8UC1; rgb8, bgr8, rgba8, bgra8 converted to
// grey) or CompressedImage (png, jpeg); the IMU sensor_msgs/msg/Imu; the
// optional ground truth geometry_msgs/msg/PoseStamped, TransformStamped or
// nav_msgs/msg/Odometry. A recording carries no calibration.
//
// Streamed like ReadBag: ReadRos2Bag keeps the IMU, the ground truth, the
// image stamps and where each image message lives; Ros2StereoImageReader
// (or Ros2ImageReader, one topic in order) decodes one image at a time.
#include <memory>
#include <string>

#include <opencv2/core.hpp>

#include "vio/dataset/euroc_dataset.h"
#include "vio/dataset/rosbag_dataset.h"

namespace vio::tools {

/// True when `path` is a .mcap or .db3 file, or a folder with metadata.yaml.
bool IsRos2BagPath(const std::string& path);

/// ReadBag's result for a ROS 2 recording: IMU, ground truth (when its topic
/// is in the recording), image stamps; `image_bag`/`image_topics` set.
/// Throws DatasetError naming the file, topic and message on a missing topic
/// (listing the recording's topics and types), a wrong type or image
/// encoding, unsorted or duplicated stamps, or a truncated or corrupt file.
EurocDataset ReadRos2Bag(const std::string& path, const BagTopics& topics);

/// The images of one camera topic in message order (8-bit grey), decoded one
/// at a time (reading backwards restarts from the first message).
class Ros2ImageReader {
 public:
  Ros2ImageReader(const std::string& path, const std::string& topic);
  ~Ros2ImageReader();
  Ros2ImageReader(Ros2ImageReader&&) noexcept;
  Ros2ImageReader& operator=(Ros2ImageReader&&) noexcept;
  /// The index-th image. Throws DatasetError past the end or on a bad message.
  cv::Mat Read(size_t index);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Both cameras' images of a recording read by ReadRos2Bag, each read where
/// that first read found it (`dataset.ros2_images`), in any order: an MCAP
/// chunk is decompressed once for both cameras while it is one of the last
/// two used (its CRC was checked by ReadRos2Bag), a .db3 row read by its id.
/// Memory stays at two chunks.
class Ros2StereoImageReader {
 public:
  /// Throws DatasetError when `dataset` was not read by ReadRos2Bag.
  explicit Ros2StereoImageReader(const EurocDataset& dataset);
  ~Ros2StereoImageReader();
  Ros2StereoImageReader(Ros2StereoImageReader&&) noexcept;
  Ros2StereoImageReader& operator=(Ros2StereoImageReader&&) noexcept;
  /// The index-th image of camera 0 or 1. Throws DatasetError past the end or on a bad message.
  cv::Mat Read(int camera, size_t index);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct Ros2WriteOptions {
  std::string storage = "mcap";      ///< mcap or sqlite3, for a bag folder (no .mcap/.db3 extension)
  std::string compression = "zstd";  ///< MCAP chunks: zstd, lz4 or none
};

/// Writes `dataset` (an ASL folder read by ReadEuroc, with images) as a ROS 2
/// recording, messages in stamp order: FILE.mcap, FILE.db3, or else a bag
/// folder (metadata.yaml and <name>_0.mcap or .db3). Images are mono8
/// sensor_msgs/msg/Image, ground truth PoseStamped. Throws DatasetError.
void WriteRos2Bag(const EurocDataset& dataset, const std::string& path, const BagTopics& topics,
                  const Ros2WriteOptions& options);

}  // namespace vio::tools
