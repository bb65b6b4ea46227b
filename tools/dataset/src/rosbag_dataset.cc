// ROS 1 bags through librosbag-storage (no ROS installation).
#include "vio/dataset/rosbag_dataset.h"

#include <filesystem>
#include <limits>
#include <optional>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <opencv2/imgcodecs.hpp>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>

#include "vio/dataset/image_file.h"
#include "vio/dataset/ros2_dataset.h"

namespace vio::tools {
namespace {

constexpr const char* kImageType = "sensor_msgs/Image";
constexpr const char* kImuType = "sensor_msgs/Imu";

// Opens for reading; a truncated or damaged bag is a DatasetError.
void OpenBag(rosbag::Bag& bag, const std::string& path) {
  try {
    bag.open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& e) {
    throw DatasetError(path + ": cannot read the ROS bag (truncated or not a bag?): " + e.what());
  }
}

// The type of `topic` in the bag, or nothing when absent.
std::optional<std::string> TopicType(const rosbag::Bag& bag, const std::string& topic) {
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  for (const rosbag::ConnectionInfo* c : view.getConnections()) return c->datatype;
  return std::nullopt;
}

std::string TopicList(const rosbag::Bag& bag) {
  rosbag::View view(bag);
  std::string list;
  for (const rosbag::ConnectionInfo* c : view.getConnections()) {
    list += (list.empty() ? "" : ", ") + c->topic + " (" + c->datatype + ")";
  }
  return list.empty() ? "none" : list;
}

void RequireTopic(const rosbag::Bag& bag, const std::string& path, const std::string& topic, const std::string& type) {
  const std::optional<std::string> found = TopicType(bag, topic);
  if (!found) {
    throw DatasetError(path + ": no topic " + topic + " (" + type + "); the bag has: " + TopicList(bag) +
                       " (set the topic names with --cam0_topic, --cam1_topic, --imu_topic)");
  }
  if (*found != type) throw DatasetError(path + ": topic " + topic + " is " + *found + ", expected " + type);
}

// Header stamps must increase strictly, message by message.
void CheckStamp(const std::string& path, const std::string& topic, size_t index, Timestamp previous, Timestamp t) {
  if (index > 0 && t <= previous) {
    throw DatasetError(path + ": " + topic + " message " + std::to_string(index) + ": stamp " + std::to_string(t) +
                       (t == previous ? " duplicates" : " is before") + " the previous one " +
                       std::to_string(previous) + " (stamps must increase)");
  }
}

Timestamp Nanos(const ros::Time& t) {
  if (t.toNSec() > static_cast<std::uint64_t>(std::numeric_limits<Timestamp>::max())) return -1;
  return static_cast<Timestamp>(t.toNSec());
}

void CheckImage(const std::string& path, const std::string& topic, size_t index, const sensor_msgs::Image& image) {
  if (image.encoding != "mono8" && image.encoding != "8UC1") {
    throw DatasetError(path + ": " + topic + " message " + std::to_string(index) + ": image encoding '" +
                       image.encoding + "', expected mono8 (8-bit grey)");
  }
  if (image.width == 0 || image.height == 0 || image.step < image.width ||
      image.data.size() < static_cast<size_t>(image.step) * image.height) {
    throw DatasetError(path + ": " + topic + " message " + std::to_string(index) + ": " + std::to_string(image.width) +
                       "x" + std::to_string(image.height) + " image with step " + std::to_string(image.step) +
                       " and " + std::to_string(image.data.size()) + " bytes is inconsistent");
  }
}

std::vector<CameraFrame> ReadImageStamps(const rosbag::Bag& bag, const std::string& path, const std::string& topic) {
  RequireTopic(bag, path, topic, kImageType);
  std::vector<CameraFrame> frames;
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  for (const rosbag::MessageInstance& m : view) {
    const sensor_msgs::Image::ConstPtr image = m.instantiate<sensor_msgs::Image>();
    CheckImage(path, topic, frames.size(), *image);
    const Timestamp t = Nanos(image->header.stamp);
    CheckStamp(path, topic, frames.size(), frames.empty() ? 0 : frames.back().t_ns, t);
    frames.push_back({t, std::to_string(t) + ".png"});
  }
  return frames;
}

std::vector<ImuSample> ReadImu(const rosbag::Bag& bag, const std::string& path, const std::string& topic) {
  RequireTopic(bag, path, topic, kImuType);
  std::vector<ImuSample> imu;
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  for (const rosbag::MessageInstance& m : view) {
    const sensor_msgs::Imu::ConstPtr msg = m.instantiate<sensor_msgs::Imu>();
    ImuSample s;
    s.t_ns = Nanos(msg->header.stamp);
    CheckStamp(path, topic, imu.size(), imu.empty() ? 0 : imu.back().t_ns, s.t_ns);
    s.gyro_rad_s = Eigen::Vector3d(msg->angular_velocity.x, msg->angular_velocity.y, msg->angular_velocity.z);
    s.accel_m_s2 = Eigen::Vector3d(msg->linear_acceleration.x, msg->linear_acceleration.y, msg->linear_acceleration.z);
    if (!s.gyro_rad_s.allFinite() || !s.accel_m_s2.allFinite()) {
      throw DatasetError(path + ": " + topic + " message " + std::to_string(imu.size()) + ": non-finite value");
    }
    imu.push_back(s);
  }
  return imu;
}

GroundTruthState PoseState(const std_msgs::Header& header, const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  GroundTruthState s;
  s.t_ns = Nanos(header.stamp);
  s.p_w_b = p;
  s.q_w_b = q.normalized();
  s.has_velocity_and_biases = false;
  return s;
}

std::optional<GroundTruthState> GroundTruthOf(const rosbag::MessageInstance& m) {
  if (const auto pose = m.instantiate<geometry_msgs::PoseStamped>()) {
    const auto& p = pose->pose.position;
    const auto& q = pose->pose.orientation;
    return PoseState(pose->header, Eigen::Vector3d(p.x, p.y, p.z), Eigen::Quaterniond(q.w, q.x, q.y, q.z));
  }
  if (const auto tf = m.instantiate<geometry_msgs::TransformStamped>()) {
    const auto& p = tf->transform.translation;
    const auto& q = tf->transform.rotation;
    return PoseState(tf->header, Eigen::Vector3d(p.x, p.y, p.z), Eigen::Quaterniond(q.w, q.x, q.y, q.z));
  }
  return std::nullopt;
}

std::vector<GroundTruthState> ReadGroundTruth(const rosbag::Bag& bag, const std::string& path,
                                              const std::string& topic) {
  std::vector<GroundTruthState> gt;
  if (topic.empty() || !TopicType(bag, topic)) return gt;
  rosbag::View view(bag, rosbag::TopicQuery(topic));
  for (const rosbag::MessageInstance& m : view) {
    const std::optional<GroundTruthState> s = GroundTruthOf(m);
    if (!s) {
      throw DatasetError(path + ": ground-truth topic " + topic + " is " + m.getDataType() +
                         ", expected geometry_msgs/PoseStamped or geometry_msgs/TransformStamped");
    }
    CheckStamp(path, topic, gt.size(), gt.empty() ? 0 : gt.back().t_ns, s->t_ns);
    gt.push_back(*s);
  }
  return gt;
}

ros::Time RosTime(Timestamp t_ns) {
  ros::Time t;
  t.fromNSec(static_cast<std::uint64_t>(t_ns));
  return t;
}

sensor_msgs::Image ImageMessage(const cv::Mat& grey, Timestamp t_ns, std::uint32_t seq) {
  sensor_msgs::Image msg;
  msg.header.stamp = RosTime(t_ns);
  msg.header.seq = seq;
  msg.height = static_cast<std::uint32_t>(grey.rows);
  msg.width = static_cast<std::uint32_t>(grey.cols);
  msg.encoding = "mono8";
  msg.step = msg.width;
  msg.data.resize(static_cast<size_t>(grey.rows) * grey.cols);
  for (int r = 0; r < grey.rows; ++r) std::copy_n(grey.ptr<std::uint8_t>(r), grey.cols, &msg.data[r * msg.step]);
  return msg;
}

void WriteImuMessages(rosbag::Bag& bag, const std::vector<ImuSample>& imu, const std::string& topic) {
  std::uint32_t seq = 0;
  for (const ImuSample& s : imu) {
    sensor_msgs::Imu msg;
    msg.header.stamp = RosTime(s.t_ns);
    msg.header.seq = seq++;
    msg.header.frame_id = "imu0";
    msg.angular_velocity.x = s.gyro_rad_s.x();
    msg.angular_velocity.y = s.gyro_rad_s.y();
    msg.angular_velocity.z = s.gyro_rad_s.z();
    msg.linear_acceleration.x = s.accel_m_s2.x();
    msg.linear_acceleration.y = s.accel_m_s2.y();
    msg.linear_acceleration.z = s.accel_m_s2.z();
    msg.orientation_covariance[0] = -1.0;  // no orientation (sensor_msgs/Imu convention)
    bag.write(topic, msg.header.stamp, msg);
  }
}

void WriteGroundTruthMessages(rosbag::Bag& bag, const std::vector<GroundTruthState>& gt, const std::string& topic) {
  std::uint32_t seq = 0;
  for (const GroundTruthState& s : gt) {
    geometry_msgs::PoseStamped msg;
    msg.header.stamp = RosTime(s.t_ns);
    msg.header.seq = seq++;
    msg.header.frame_id = "world";
    msg.pose.position.x = s.p_w_b.x();
    msg.pose.position.y = s.p_w_b.y();
    msg.pose.position.z = s.p_w_b.z();
    msg.pose.orientation.w = s.q_w_b.w();
    msg.pose.orientation.x = s.q_w_b.x();
    msg.pose.orientation.y = s.q_w_b.y();
    msg.pose.orientation.z = s.q_w_b.z();
    bag.write(topic, msg.header.stamp, msg);
  }
}

void WriteCameraMessages(rosbag::Bag& bag, const EurocDataset& dataset, int camera, const std::string& topic) {
  const std::string folder = dataset.root + "/mav0/cam" + std::to_string(camera) + "/data/";
  std::uint32_t seq = 0;
  for (const CameraFrame& f : dataset.frames[camera]) {
    const cv::Mat grey = ImageRead(folder + f.filename, cv::IMREAD_GRAYSCALE);
    if (grey.empty()) throw DatasetError(folder + f.filename + ": cannot read the image");
    sensor_msgs::Image msg = ImageMessage(grey, f.t_ns, seq++);
    msg.header.frame_id = "cam" + std::to_string(camera);
    bag.write(topic, msg.header.stamp, msg);
  }
}

}  // namespace

bool IsBagPath(const std::string& path) {
  std::error_code ec;
  return std::filesystem::path(path).extension() == ".bag" && std::filesystem::is_regular_file(path, ec);
}

EurocDataset ReadBag(const std::string& path, const BagTopics& topics) {
  rosbag::Bag bag;
  OpenBag(bag, path);
  EurocDataset dataset;
  dataset.root = path;
  try {
    dataset.imu = ReadImu(bag, path, topics.imu_topic);
    const std::string* camera_topics[2] = {&topics.cam0_topic, &topics.cam1_topic};
    for (int i = 0; i < 2; ++i) {
      dataset.frames[i] = ReadImageStamps(bag, path, *camera_topics[i]);
      dataset.image_topics[i] = *camera_topics[i];
    }
    dataset.groundtruth = ReadGroundTruth(bag, path, topics.groundtruth_topic);
  } catch (const rosbag::BagException& e) {
    throw DatasetError(path + ": cannot read the ROS bag (truncated?): " + e.what());
  }
  dataset.image_bag = path;
  dataset.has_images = !dataset.frames[0].empty() && !dataset.frames[1].empty();
  return dataset;
}

struct BagImageReader::Impl {
  std::string path, topic;
  rosbag::Bag bag;
  std::unique_ptr<rosbag::View> view;
  rosbag::View::iterator it;
  size_t next = 0;  ///< index of the message `it` points to

  void Restart() {
    view = std::make_unique<rosbag::View>(bag, rosbag::TopicQuery(topic));
    it = view->begin();
    next = 0;
  }
};

BagImageReader::BagImageReader(const std::string& path, const std::string& topic) : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  impl_->topic = topic;
  OpenBag(impl_->bag, path);
  impl_->Restart();
}

BagImageReader::~BagImageReader() = default;
BagImageReader::BagImageReader(BagImageReader&&) noexcept = default;
BagImageReader& BagImageReader::operator=(BagImageReader&&) noexcept = default;

cv::Mat BagImageReader::Read(size_t index) {
  Impl& r = *impl_;
  try {
    if (index < r.next) r.Restart();
    for (; r.it != r.view->end() && r.next < index; ++r.it) ++r.next;
    if (r.it == r.view->end()) {
      throw DatasetError(r.path + ": " + r.topic + " has no message " + std::to_string(index));
    }
    const sensor_msgs::Image::ConstPtr image = r.it->instantiate<sensor_msgs::Image>();
    CheckImage(r.path, r.topic, index, *image);
    cv::Mat grey(static_cast<int>(image->height), static_cast<int>(image->width), CV_8UC1);
    for (int row = 0; row < grey.rows; ++row) {
      std::copy_n(&image->data[static_cast<size_t>(row) * image->step], grey.cols, grey.ptr<std::uint8_t>(row));
    }
    return grey;
  } catch (const rosbag::BagException& e) {
    throw DatasetError(r.path + ": cannot read " + r.topic + " message " + std::to_string(index) +
                       " (truncated bag?): " + e.what());
  }
}

void WriteBag(const EurocDataset& dataset, const std::string& path, const BagTopics& topics) {
  rosbag::Bag bag;
  try {
    bag.open(path, rosbag::bagmode::Write);
    WriteImuMessages(bag, dataset.imu, topics.imu_topic);
    if (!dataset.groundtruth.empty() && !topics.groundtruth_topic.empty()) {
      WriteGroundTruthMessages(bag, dataset.groundtruth, topics.groundtruth_topic);
    }
    WriteCameraMessages(bag, dataset, 0, topics.cam0_topic);
    WriteCameraMessages(bag, dataset, 1, topics.cam1_topic);
    bag.close();
  } catch (const rosbag::BagException& e) {
    throw DatasetError(path + ": cannot write the ROS bag: " + e.what());
  }
}

void WriteAslFromBag(const EurocDataset& dataset, const std::string& root) {
  EurocDataset asl = dataset;
  asl.image_bag.clear();
  WriteEuroc(asl, root);
  std::optional<Ros2StereoImageReader> ros2_images;
  if (dataset.ros2_images) ros2_images.emplace(dataset);
  for (int camera = 0; camera < 2; ++camera) {
    const std::string folder = root + "/mav0/cam" + std::to_string(camera) + "/data/";
    std::filesystem::create_directories(folder);
    std::optional<BagImageReader> ros1;
    std::optional<Ros2ImageReader> ros2;
    if (!ros2_images && IsRos2BagPath(dataset.image_bag)) {
      ros2.emplace(dataset.image_bag, dataset.image_topics[camera]);
    } else if (!ros2_images) {
      ros1.emplace(dataset.image_bag, dataset.image_topics[camera]);
    }
    for (size_t k = 0; k < dataset.frames[camera].size(); ++k) {
      const std::string file = folder + dataset.frames[camera][k].filename;
      const cv::Mat image = ros2_images ? ros2_images->Read(camera, k) : ros2 ? ros2->Read(k) : ros1->Read(k);
      if (!ImageWrite(file, image)) throw DatasetError(file + ": cannot write the image");
    }
  }
}

}  // namespace vio::tools
