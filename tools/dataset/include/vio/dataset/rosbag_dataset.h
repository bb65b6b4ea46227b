#pragma once
// ROS 1 bags without ROS (Debian's librosbag-storage): a stereo-inertial
// recording as sensor_msgs/Image stereo topics, sensor_msgs/Imu and an
// optional ground-truth topic (geometry_msgs/PoseStamped or
// TransformStamped). A bag carries no calibration: the caller takes it from a
// folder of EuRoC sensor.yaml files.
//
// Streamed: ReadBag keeps the IMU and ground truth (small) and only the stamps
// of the images; BagImageReader decodes one image at a time, in order.
#include <memory>
#include <string>

#include <opencv2/core.hpp>

#include "vio/dataset/euroc_dataset.h"

namespace vio::tools {

/// The bag's topics (defaults: the EuRoC bags').
struct BagTopics {
  std::string cam0_topic = "/cam0/image_raw";
  std::string cam1_topic = "/cam1/image_raw";
  std::string imu_topic = "/imu0";
  /// geometry_msgs/PoseStamped or TransformStamped (body in world); optional.
  std::string groundtruth_topic = "/groundtruth";

  template <class V>
  void Visit(V& v) {
    v("cam0_topic", cam0_topic,
      "ROS bag input: left camera topic (sensor_msgs/Image, mono8; ROS 2 also rgb8, bgr8, rgba8, bgra8 and "
      "CompressedImage png or jpeg)");
    v("cam1_topic", cam1_topic, "ROS bag input: right camera topic (as cam0_topic)");
    v("imu_topic", imu_topic, "ROS bag input: IMU topic (sensor_msgs/Imu)");
    v("groundtruth_topic", groundtruth_topic,
      "ROS bag input: optional ground-truth topic (geometry_msgs/PoseStamped or TransformStamped; ROS 2 also "
      "nav_msgs/Odometry)");
  }
};

/// True when `path` names a ROS bag (a regular file ending in .bag).
bool IsBagPath(const std::string& path);

/// The IMU, the ground truth (when its topic is in the bag) and the image
/// stamps of both cameras (frames[i]: one row per message, file name
/// "<stamp>.png"); `image_bag` and `image_topics` are set so the images are
/// read from the bag. Calibration is left empty. Throws DatasetError naming
/// the bag, topic and message on a missing topic, a wrong message type or
/// encoding, unsorted or duplicated stamps, or a truncated bag.
EurocDataset ReadBag(const std::string& path, const BagTopics& topics);

/// The images of one camera topic in message order, decoded one at a time
/// (reading backwards restarts from the first message).
class BagImageReader {
 public:
  BagImageReader(const std::string& path, const std::string& topic);
  ~BagImageReader();
  BagImageReader(BagImageReader&&) noexcept;
  BagImageReader& operator=(BagImageReader&&) noexcept;
  /// The index-th image (8-bit grey). Throws DatasetError past the end.
  cv::Mat Read(size_t index);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Writes `dataset` (an ASL folder read by ReadEuroc, with images) as a bag:
/// IMU, ground-truth poses (when present) and both cameras' images (read one
/// at a time from the folder). Throws DatasetError / std::runtime_error.
void WriteBag(const EurocDataset& dataset, const std::string& path, const BagTopics& topics);

/// Writes a bag's dataset (ReadBag or ReadRos2Bag, with calibration set) as
/// an ASL folder, images as PNG.
void WriteAslFromBag(const EurocDataset& dataset, const std::string& root);

}  // namespace vio::tools
