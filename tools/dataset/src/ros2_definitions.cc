// The ros2msg definitions an MCAP file carries as the schemas of the messages
// `vio convert` writes (the ROS 2 interface files, comments left out, each
// dependency after a separator line and "MSG: <type>").
#include "ros2_messages.h"

namespace vio::tools::ros2 {
namespace {

constexpr const char* kSeparator =
    "================================================================================\n";

constexpr const char* kHeaderDefinitions =
    "MSG: std_msgs/Header\n"
    "builtin_interfaces/Time stamp\n"
    "string frame_id\n";

constexpr const char* kTimeDefinition =
    "MSG: builtin_interfaces/Time\n"
    "int32 sec\n"
    "uint32 nanosec\n";

constexpr const char* kImage =
    "std_msgs/Header header\n"
    "uint32 height\n"
    "uint32 width\n"
    "string encoding\n"
    "uint8 is_bigendian\n"
    "uint32 step\n"
    "uint8[] data\n";

constexpr const char* kImu =
    "std_msgs/Header header\n"
    "geometry_msgs/Quaternion orientation\n"
    "float64[9] orientation_covariance\n"
    "geometry_msgs/Vector3 angular_velocity\n"
    "float64[9] angular_velocity_covariance\n"
    "geometry_msgs/Vector3 linear_acceleration\n"
    "float64[9] linear_acceleration_covariance\n";

constexpr const char* kPoseStamped =
    "std_msgs/Header header\n"
    "geometry_msgs/Pose pose\n";

constexpr const char* kPose =
    "MSG: geometry_msgs/Pose\n"
    "geometry_msgs/Point position\n"
    "geometry_msgs/Quaternion orientation\n";

constexpr const char* kPoint =
    "MSG: geometry_msgs/Point\n"
    "float64 x\n"
    "float64 y\n"
    "float64 z\n";

constexpr const char* kQuaternion =
    "MSG: geometry_msgs/Quaternion\n"
    "float64 x 0\n"
    "float64 y 0\n"
    "float64 z 0\n"
    "float64 w 1\n";

constexpr const char* kVector3 =
    "MSG: geometry_msgs/Vector3\n"
    "float64 x\n"
    "float64 y\n"
    "float64 z\n";

std::string Join(std::initializer_list<const char*> parts) {
  std::string text;
  for (const char* part : parts) text += (text.empty() ? "" : kSeparator) + std::string(part);
  return text;
}

}  // namespace

std::string MessageDefinition(const std::string& type) {
  if (type == kImageType) return Join({kImage, kHeaderDefinitions, kTimeDefinition});
  if (type == kImuType) return Join({kImu, kHeaderDefinitions, kTimeDefinition, kQuaternion, kVector3});
  if (type == kPoseStampedType) return Join({kPoseStamped, kHeaderDefinitions, kTimeDefinition, kPose, kPoint, kQuaternion});
  throw Ros2MessageError("no message definition for " + type);
}

}  // namespace vio::tools::ros2
