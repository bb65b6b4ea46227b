// ROS 2 message definitions (ros2msg text, dependencies after separator lines) as
// ROS 2's interface packages define them: what write_bag.js serializes and puts in
// the MCAP schemas.
"use strict";
const SEP = "================================================================================\n";
const dep = {
  "std_msgs/Header": "builtin_interfaces/Time stamp\nstring frame_id\n",
  "builtin_interfaces/Time": "int32 sec\nuint32 nanosec\n",
  "geometry_msgs/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
  "geometry_msgs/Vector3": "float64 x\nfloat64 y\nfloat64 z\n",
  "geometry_msgs/Point": "float64 x\nfloat64 y\nfloat64 z\n",
  "geometry_msgs/Pose": "Point position\nQuaternion orientation\n",
  "geometry_msgs/Transform": "Vector3 translation\nQuaternion rotation\n",
  "geometry_msgs/PoseWithCovariance": "Pose pose\nfloat64[36] covariance\n",
  "geometry_msgs/Twist": "Vector3  linear\nVector3  angular\n",
  "geometry_msgs/TwistWithCovariance": "Twist twist\nfloat64[36] covariance\n",
};
function def(main, deps) {
  return main + deps.map((d) => `${SEP}MSG: ${d}\n${dep[d]}`).join("");
}
const header = ["std_msgs/Header", "builtin_interfaces/Time"];
module.exports = {
  "sensor_msgs/msg/Image": def("std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n" +
                               "uint8 is_bigendian\nuint32 step\nuint8[] data\n", header),
  "sensor_msgs/msg/CompressedImage": def("std_msgs/Header header\nstring format\nuint8[] data\n", header),
  "sensor_msgs/msg/Imu": def("std_msgs/Header header\ngeometry_msgs/Quaternion orientation\n" +
                             "float64[9] orientation_covariance\ngeometry_msgs/Vector3 angular_velocity\n" +
                             "float64[9] angular_velocity_covariance\ngeometry_msgs/Vector3 linear_acceleration\n" +
                             "float64[9] linear_acceleration_covariance\n",
                             [...header, "geometry_msgs/Quaternion", "geometry_msgs/Vector3"]),
  "geometry_msgs/msg/PoseStamped": def("std_msgs/Header header\nPose pose\n",
                                       [...header, "geometry_msgs/Pose", "geometry_msgs/Point", "geometry_msgs/Quaternion"]),
  "geometry_msgs/msg/TransformStamped": def("std_msgs/Header header\nstring child_frame_id\nTransform transform\n",
                                            [...header, "geometry_msgs/Transform", "geometry_msgs/Vector3",
                                             "geometry_msgs/Quaternion"]),
  "nav_msgs/msg/Odometry": def("std_msgs/Header header\nstring child_frame_id\n" +
                               "geometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist\n",
                               [...header, "geometry_msgs/PoseWithCovariance", "geometry_msgs/Pose", "geometry_msgs/Point",
                                "geometry_msgs/Quaternion", "geometry_msgs/TwistWithCovariance", "geometry_msgs/Twist",
                                "geometry_msgs/Vector3"]),
};
