// A ROS 2 recording read into an EurocDataset (stamps only for the images),
// its images one at a time.
#include "vio/dataset/ros2_dataset.h"

#include <filesystem>

#include "ros2_messages.h"
#include "ros2_storage.h"

namespace vio::tools {
namespace {

using ros2::Message;

std::string Where(const std::string& file, const std::string& topic, size_t index) {
  return file + ": " + topic + " message " + std::to_string(index) + ": ";
}

void CheckStamp(const std::string& where, Timestamp previous, Timestamp t, size_t index) {
  if (index > 0 && t <= previous) {
    throw DatasetError(where + "stamp " + std::to_string(t) + (t == previous ? " duplicates" : " is before") +
                       " the previous one " + std::to_string(previous) + " (stamps must increase)");
  }
}

void CheckType(const std::string& where, const ros2::Topic& topic, std::initializer_list<const char*> types) {
  std::string expected;
  for (const char* type : types) {
    if (topic.type == type && topic.encoding == "cdr") return;
    expected += (expected.empty() ? "" : " or ") + std::string(type);
  }
  if (topic.encoding != "cdr") throw DatasetError(where + "encoded as '" + topic.encoding + "', expected cdr");
  throw DatasetError(where + "topic " + topic.name + " is " + topic.type + ", expected " + expected);
}

// Reads the recording's messages of the four topics into `dataset`.
class DatasetBuilder {
 public:
  DatasetBuilder(const BagTopics& topics, EurocDataset* dataset) : topics_(topics), dataset_(*dataset) {}

  void Add(const std::string& file, const Message& m) {
    const std::string& name = m.topic->name;
    try {
      if (name == topics_.imu_topic) AddImu(file, m);
      if (name == topics_.cam0_topic) AddImage(file, m, 0);
      if (name == topics_.cam1_topic) AddImage(file, m, 1);
      if (name == topics_.groundtruth_topic) AddPose(file, m);
    } catch (const ros2::CdrError& e) {
      throw DatasetError(Where(file, name, Count(name)) + e.what());
    } catch (const ros2::Ros2MessageError& e) {
      throw DatasetError(Where(file, name, Count(name)) + e.what());
    }
  }

 private:
  size_t Count(const std::string& name) const {
    if (name == topics_.imu_topic) return dataset_.imu.size();
    if (name == topics_.cam0_topic) return dataset_.frames[0].size();
    if (name == topics_.cam1_topic) return dataset_.frames[1].size();
    return dataset_.groundtruth.size();
  }

  void AddImu(const std::string& file, const Message& m) {
    std::vector<ImuSample>& imu = dataset_.imu;
    const std::string where = Where(file, m.topic->name, imu.size());
    CheckType(where, *m.topic, {ros2::kImuType});
    const ImuSample s = ros2::DecodeImu(m.data, m.size);
    CheckStamp(where, imu.empty() ? 0 : imu.back().t_ns, s.t_ns, imu.size());
    imu.push_back(s);
  }

  void AddImage(const std::string& file, const Message& m, int camera) {
    std::vector<CameraFrame>& frames = dataset_.frames[camera];
    const std::string where = Where(file, m.topic->name, frames.size());
    CheckType(where, *m.topic, {ros2::kImageType, ros2::kCompressedImageType});
    ros2::CheckImage(m.topic->type, m.data, m.size);
    const Timestamp t = ros2::HeaderStamp(m.data, m.size);
    CheckStamp(where, frames.empty() ? 0 : frames.back().t_ns, t, frames.size());
    frames.push_back({t, std::to_string(t) + ".png"});
  }

  void AddPose(const std::string& file, const Message& m) {
    std::vector<GroundTruthState>& gt = dataset_.groundtruth;
    const std::string where = Where(file, m.topic->name, gt.size());
    CheckType(where, *m.topic, {ros2::kPoseStampedType, ros2::kTransformStampedType, ros2::kOdometryType});
    const GroundTruthState s = ros2::DecodePose(m.topic->type, m.data, m.size);
    CheckStamp(where, gt.empty() ? 0 : gt.back().t_ns, s.t_ns, gt.size());
    gt.push_back(s);
  }

  const BagTopics& topics_;
  EurocDataset& dataset_;
};

// A required topic without messages: absent (list the recording's topics),
// of another type, or empty.
void RequireMessages(const std::string& path, const std::vector<ros2::Topic>& all, const std::string& topic,
                     const std::string& type, size_t count) {
  if (count > 0) return;
  std::string list;
  for (const ros2::Topic& t : all) {
    if (t.name == topic) throw DatasetError(path + ": topic " + topic + " (" + t.type + ") has no messages");
    list += (list.empty() ? "" : ", ") + t.name + " (" + t.type + ")";
  }
  throw DatasetError(path + ": no topic " + topic + " (" + type + "); the recording has: " +
                     (list.empty() ? "none" : list) + " (set the topic names with --cam0_topic, --cam1_topic, "
                     "--imu_topic)");
}

}  // namespace

bool IsRos2BagPath(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_directory(path, ec)) return fs::is_regular_file(fs::path(path) / "metadata.yaml", ec);
  const fs::path extension = fs::path(path).extension();
  return (extension == ".mcap" || extension == ".db3") && fs::is_regular_file(path, ec);
}

EurocDataset ReadRos2Bag(const std::string& path, const BagTopics& topics) {
  std::set<std::string> names = {topics.imu_topic, topics.cam0_topic, topics.cam1_topic};
  if (!topics.groundtruth_topic.empty()) names.insert(topics.groundtruth_topic);
  ros2::BagReader reader(ros2::ResolveBag(path), names);
  EurocDataset dataset;
  dataset.root = path;
  DatasetBuilder builder(topics, &dataset);
  Message m;
  while (reader.Next(&m)) builder.Add(reader.file(), m);
  const std::vector<ros2::Topic> all = reader.Topics();
  RequireMessages(path, all, topics.imu_topic, ros2::kImuType, dataset.imu.size());
  RequireMessages(path, all, topics.cam0_topic, ros2::kImageType, dataset.frames[0].size());
  RequireMessages(path, all, topics.cam1_topic, ros2::kImageType, dataset.frames[1].size());
  dataset.image_bag = path;
  dataset.image_topics[0] = topics.cam0_topic;
  dataset.image_topics[1] = topics.cam1_topic;
  dataset.has_images = true;
  return dataset;
}

struct Ros2ImageReader::Impl {
  ros2::BagFiles bag;
  std::string topic;
  std::unique_ptr<ros2::BagReader> reader;
  size_t next = 0;  ///< index of the message the next Next() returns

  void Restart() {
    reader = std::make_unique<ros2::BagReader>(bag, std::set<std::string>{topic});
    next = 0;
  }
};

Ros2ImageReader::Ros2ImageReader(const std::string& path, const std::string& topic)
    : impl_(std::make_unique<Impl>()) {
  impl_->bag = ros2::ResolveBag(path);
  impl_->topic = topic;
  impl_->Restart();
}

Ros2ImageReader::~Ros2ImageReader() = default;
Ros2ImageReader::Ros2ImageReader(Ros2ImageReader&&) noexcept = default;
Ros2ImageReader& Ros2ImageReader::operator=(Ros2ImageReader&&) noexcept = default;

cv::Mat Ros2ImageReader::Read(size_t index) {
  Impl& r = *impl_;
  if (index < r.next) r.Restart();
  Message m;
  for (;;) {
    if (!r.reader->Next(&m)) throw DatasetError(r.bag.path + ": " + r.topic + " has no message " + std::to_string(index));
    if (r.next++ == index) break;
  }
  const std::string where = Where(r.reader->file(), r.topic, index);
  try {
    CheckType(where, *m.topic, {ros2::kImageType, ros2::kCompressedImageType});
    Timestamp stamp = 0;
    return ros2::DecodeGreyImage(m.topic->type, m.data, m.size, &stamp);
  } catch (const ros2::CdrError& e) {
    throw DatasetError(where + e.what());
  } catch (const ros2::Ros2MessageError& e) {
    throw DatasetError(where + e.what());
  }
}

}  // namespace vio::tools
