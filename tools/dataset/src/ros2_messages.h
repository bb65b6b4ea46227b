#pragma once
// The ROS 2 messages a stereo-inertial recording holds, decoded from and
// encoded to CDR (cdr.h): sensor_msgs/msg/Image and CompressedImage,
// sensor_msgs/msg/Imu, and ground truth as geometry_msgs/msg/PoseStamped,
// TransformStamped or nav_msgs/msg/Odometry. Decoders throw CdrError (bad
// bytes) or Ros2MessageError (a value this project cannot use); the caller
// adds the file, topic and message.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "cdr.h"
#include "vio/dataset/euroc_dataset.h"

namespace vio::tools::ros2 {

class Ros2MessageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

constexpr const char* kImageType = "sensor_msgs/msg/Image";
constexpr const char* kCompressedImageType = "sensor_msgs/msg/CompressedImage";
constexpr const char* kImuType = "sensor_msgs/msg/Imu";
constexpr const char* kPoseStampedType = "geometry_msgs/msg/PoseStamped";
constexpr const char* kTransformStampedType = "geometry_msgs/msg/TransformStamped";
constexpr const char* kOdometryType = "nav_msgs/msg/Odometry";

/// `type` in the pkg/msg/Name form (ROS 1's pkg/Name gets its /msg/).
std::string CanonicalType(const std::string& type);

/// The header stamp of any message that starts with std_msgs/Header (all of
/// the above) [ns]; throws Ros2MessageError when negative.
Timestamp HeaderStamp(const std::uint8_t* data, size_t size);

/// An image message as 8-bit grey. Image: mono8/8UC1 as is; rgb8, bgr8,
/// rgba8, bgra8 converted; CompressedImage: png or jpeg, decoded as grey.
/// Throws Ros2MessageError on another encoding or inconsistent sizes.
cv::Mat DecodeGreyImage(const std::string& type, const std::uint8_t* data, size_t size, Timestamp* stamp);

/// Checks what DecodeGreyImage checks without decoding pixels (for a scan).
void CheckImage(const std::string& type, const std::uint8_t* data, size_t size);

ImuSample DecodeImu(const std::uint8_t* data, size_t size);

/// A pose message of one of the three ground-truth types as body in world.
GroundTruthState DecodePose(const std::string& type, const std::uint8_t* data, size_t size);

std::vector<std::uint8_t> EncodeImage(const cv::Mat& grey, Timestamp t_ns, const std::string& frame_id);
std::vector<std::uint8_t> EncodeImu(const ImuSample& s, const std::string& frame_id);
std::vector<std::uint8_t> EncodePoseStamped(const GroundTruthState& s, const std::string& frame_id);

/// The message definition (ros2msg text with its dependencies, as MCAP
/// schemas carry it) of Image, Imu or PoseStamped.
std::string MessageDefinition(const std::string& type);

}  // namespace vio::tools::ros2
