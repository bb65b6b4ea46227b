#include "ros2_messages.h"

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "vio/dataset/image_file.h"

namespace vio::tools::ros2 {
namespace {

constexpr std::int64_t kNsPerS = 1'000'000'000;

Timestamp ReadHeader(CdrReader& r) {
  const std::int32_t sec = r.I32();
  const std::uint32_t nanosec = r.U32();
  r.String();  // frame_id
  if (sec < 0 || nanosec >= kNsPerS) {
    throw Ros2MessageError("header stamp " + std::to_string(sec) + " s " + std::to_string(nanosec) +
                           " ns is not a valid time (negative or nanoseconds >= 1e9)");
  }
  return sec * kNsPerS + nanosec;
}

void WriteHeader(CdrWriter& w, Timestamp t_ns, const std::string& frame_id) {
  w.I32(static_cast<std::int32_t>(t_ns / kNsPerS));
  w.U32(static_cast<std::uint32_t>(t_ns % kNsPerS));
  w.String(frame_id);
}

Eigen::Vector3d ReadVector3(CdrReader& r) {
  const double x = r.F64(), y = r.F64(), z = r.F64();
  return Eigen::Vector3d(x, y, z);
}

// geometry_msgs Quaternion: x, y, z, w.
Eigen::Quaterniond ReadQuaternion(CdrReader& r) {
  const double x = r.F64(), y = r.F64(), z = r.F64(), w = r.F64();
  return Eigen::Quaterniond(w, x, y, z);
}

struct RawImage {
  Timestamp stamp = 0;
  std::uint32_t height = 0, width = 0, step = 0;
  std::string encoding;
  const std::uint8_t* data = nullptr;
  size_t size = 0;
};

// Channels of the encodings that convert to grey; 0 for any other.
int Channels(const std::string& encoding) {
  if (encoding == "mono8" || encoding == "8UC1") return 1;
  if (encoding == "rgb8" || encoding == "bgr8") return 3;
  if (encoding == "rgba8" || encoding == "bgra8") return 4;
  return 0;
}

RawImage ReadRawImage(const std::uint8_t* data, size_t size) {
  CdrReader r(data, size);
  RawImage image;
  image.stamp = ReadHeader(r);
  image.height = r.U32();
  image.width = r.U32();
  image.encoding = r.String();
  r.U8();  // is_bigendian: no 8-bit encoding cares
  image.step = r.U32();
  image.data = r.Bytes(&image.size);
  const int channels = Channels(image.encoding);
  if (channels == 0) {
    throw Ros2MessageError("image encoding '" + image.encoding + "' cannot be used (mono8, 8UC1, rgb8, bgr8, rgba8 "
                           "or bgra8; or sensor_msgs/msg/CompressedImage png or jpeg)");
  }
  if (image.width == 0 || image.height == 0 || image.step < static_cast<std::uint64_t>(image.width) * channels ||
      image.size < static_cast<size_t>(image.step) * image.height) {
    throw Ros2MessageError(std::to_string(image.width) + "x" + std::to_string(image.height) + " " + image.encoding +
                           " image with step " + std::to_string(image.step) + " and " +
                           std::to_string(image.size) + " bytes is inconsistent");
  }
  return image;
}

struct RawCompressed {
  Timestamp stamp = 0;
  const std::uint8_t* data = nullptr;
  size_t size = 0;
};

RawCompressed ReadRawCompressed(const std::uint8_t* data, size_t size) {
  CdrReader r(data, size);
  RawCompressed image;
  image.stamp = ReadHeader(r);
  const std::string format = r.String();
  image.data = r.Bytes(&image.size);
  const bool known = format.find("png") != std::string::npos || format.find("jpeg") != std::string::npos ||
                     format.find("jpg") != std::string::npos;
  if (!known || format.find("compressedDepth") != std::string::npos) {
    throw Ros2MessageError("compressed image format '" + format + "' cannot be used (png or jpeg)");
  }
  return image;
}

cv::Mat GreyOf(const RawImage& image) {
  const int channels = Channels(image.encoding);
  const cv::Mat view(static_cast<int>(image.height), static_cast<int>(image.width), CV_8UC(channels),
                     const_cast<std::uint8_t*>(image.data), image.step);
  cv::Mat grey;
  if (channels == 1) {
    grey = view.clone();
  } else {
    const bool rgb = image.encoding[0] == 'r';
    const int code = channels == 3 ? (rgb ? cv::COLOR_RGB2GRAY : cv::COLOR_BGR2GRAY)
                                   : (rgb ? cv::COLOR_RGBA2GRAY : cv::COLOR_BGRA2GRAY);
    cv::cvtColor(view, grey, code);
  }
  return grey;
}

}  // namespace

std::string CanonicalType(const std::string& type) {
  const size_t slash = type.find('/');
  if (slash == std::string::npos || type.find("/msg/") != std::string::npos) return type;
  return type.substr(0, slash) + "/msg" + type.substr(slash);
}

Timestamp HeaderStamp(const std::uint8_t* data, size_t size) {
  CdrReader r(data, size);
  return ReadHeader(r);
}

void CheckImage(const std::string& type, const std::uint8_t* data, size_t size) {
  if (type == kCompressedImageType) {
    ReadRawCompressed(data, size);
  } else {
    ReadRawImage(data, size);
  }
}

cv::Mat DecodeGreyImage(const std::string& type, const std::uint8_t* data, size_t size, Timestamp* stamp) {
  if (type != kCompressedImageType) {
    const RawImage image = ReadRawImage(data, size);
    *stamp = image.stamp;
    return GreyOf(image);
  }
  const RawCompressed image = ReadRawCompressed(data, size);
  *stamp = image.stamp;
  const cv::Mat bytes(1, static_cast<int>(image.size), CV_8UC1, const_cast<std::uint8_t*>(image.data));
  cv::Mat grey = ImageDecode(bytes, cv::IMREAD_GRAYSCALE);
  if (grey.empty()) throw Ros2MessageError("the compressed image (" + std::to_string(image.size) + " bytes) does not decode");
  return grey;
}

ImuSample DecodeImu(const std::uint8_t* data, size_t size) {
  CdrReader r(data, size);
  ImuSample s;
  s.t_ns = ReadHeader(r);
  ReadQuaternion(r);  // orientation: not used
  r.SkipF64(9);
  s.gyro_rad_s = ReadVector3(r);
  r.SkipF64(9);
  s.accel_m_s2 = ReadVector3(r);
  r.SkipF64(9);
  if (!s.gyro_rad_s.allFinite() || !s.accel_m_s2.allFinite()) throw Ros2MessageError("non-finite IMU value");
  return s;
}

GroundTruthState DecodePose(const std::string& type, const std::uint8_t* data, size_t size) {
  CdrReader r(data, size);
  GroundTruthState s;
  s.has_velocity_and_biases = false;
  s.t_ns = ReadHeader(r);
  if (type == kTransformStampedType || type == kOdometryType) r.String();  // child_frame_id
  s.p_w_b = ReadVector3(r);
  const Eigen::Quaterniond q = ReadQuaternion(r);
  if (!s.p_w_b.allFinite() || !q.coeffs().allFinite() || q.norm() < 1e-6) {
    throw Ros2MessageError("pose with a non-finite value or a zero quaternion");
  }
  s.q_w_b = q.normalized();
  return s;
}

std::vector<std::uint8_t> EncodeImage(const cv::Mat& grey, Timestamp t_ns, const std::string& frame_id) {
  CdrWriter w;
  WriteHeader(w, t_ns, frame_id);
  w.U32(static_cast<std::uint32_t>(grey.rows));
  w.U32(static_cast<std::uint32_t>(grey.cols));
  w.String("mono8");
  w.U8(0);
  w.U32(static_cast<std::uint32_t>(grey.cols));
  const cv::Mat packed = grey.isContinuous() ? grey : grey.clone();
  w.Bytes(packed.ptr<std::uint8_t>(0), packed.total());
  return w.bytes();
}

std::vector<std::uint8_t> EncodeImu(const ImuSample& s, const std::string& frame_id) {
  CdrWriter w;
  WriteHeader(w, s.t_ns, frame_id);
  for (double v : {0.0, 0.0, 0.0, 1.0}) w.F64(v);
  // orientation_covariance[0] = -1: no orientation (the sensor_msgs/Imu convention)
  for (int i = 0; i < 9; ++i) w.F64(i == 0 ? -1.0 : 0.0);
  for (int i = 0; i < 3; ++i) w.F64(s.gyro_rad_s[i]);
  for (int i = 0; i < 9; ++i) w.F64(0.0);
  for (int i = 0; i < 3; ++i) w.F64(s.accel_m_s2[i]);
  for (int i = 0; i < 9; ++i) w.F64(0.0);
  return w.bytes();
}

std::vector<std::uint8_t> EncodePoseStamped(const GroundTruthState& s, const std::string& frame_id) {
  CdrWriter w;
  WriteHeader(w, s.t_ns, frame_id);
  for (int i = 0; i < 3; ++i) w.F64(s.p_w_b[i]);
  for (double v : {s.q_w_b.x(), s.q_w_b.y(), s.q_w_b.z(), s.q_w_b.w()}) w.F64(v);
  return w.bytes();
}

}  // namespace vio::tools::ros2
