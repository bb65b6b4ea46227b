// A ROS 2 recording read into an EurocDataset (stamps only for the images),
// its images one at a time.
#include "vio/dataset/ros2_dataset.h"

#include <filesystem>

#include "ros2_messages.h"
#include "ros2_storage.h"

namespace vio::tools {

/// Where each image message of a recording lives (ReadRos2Bag's first read).
struct Ros2ImageIndex {
  struct Image {
    ros2::MessagePlace place;
    std::uint32_t topic = 0;  ///< index into `topics`
  };
  ros2::BagFiles bag;
  std::vector<ros2::Topic> topics;  ///< the distinct image topics (name, type, encoding)
  std::vector<Image> images[2];     ///< cam0, cam1 in message order

  void Add(int camera, const ros2::Topic& topic, const ros2::MessagePlace& place) {
    std::uint32_t k = 0;
    while (k < topics.size() && (topics[k].name != topic.name || topics[k].type != topic.type ||
                                 topics[k].encoding != topic.encoding)) {
      ++k;
    }
    if (k == topics.size()) topics.push_back(topic);
    images[camera].push_back({place, k});
  }
};

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
  DatasetBuilder(const BagTopics& topics, EurocDataset* dataset, Ros2ImageIndex* index)
      : topics_(topics), dataset_(*dataset), index_(*index) {}

  void Add(const std::string& file, const Message& m, const ros2::MessagePlace& place) {
    const std::string& name = m.topic->name;
    try {
      if (name == topics_.imu_topic) AddImu(file, m);
      if (name == topics_.cam0_topic) AddImage(file, m, 0, place);
      if (name == topics_.cam1_topic) AddImage(file, m, 1, place);
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

  void AddImage(const std::string& file, const Message& m, int camera, const ros2::MessagePlace& place) {
    std::vector<CameraFrame>& frames = dataset_.frames[camera];
    const std::string where = Where(file, m.topic->name, frames.size());
    CheckType(where, *m.topic, {ros2::kImageType, ros2::kCompressedImageType});
    ros2::CheckImage(m.topic->type, m.data, m.size);
    const Timestamp t = ros2::HeaderStamp(m.data, m.size);
    CheckStamp(where, frames.empty() ? 0 : frames.back().t_ns, t, frames.size());
    frames.push_back({t, std::to_string(t) + ".png"});
    index_.Add(camera, *m.topic, place);
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
  Ros2ImageIndex& index_;
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

// The image of message `m` (at `where`), grey.
cv::Mat DecodeImage(const std::string& where, const Message& m) {
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
  auto index = std::make_shared<Ros2ImageIndex>();
  index->bag = ros2::ResolveBag(path);
  ros2::BagReader reader(index->bag, names);
  EurocDataset dataset;
  dataset.root = path;
  DatasetBuilder builder(topics, &dataset, index.get());
  Message m;
  while (reader.Next(&m)) builder.Add(reader.file(), m, reader.Place());
  const std::vector<ros2::Topic> all = reader.Topics();
  RequireMessages(path, all, topics.imu_topic, ros2::kImuType, dataset.imu.size());
  RequireMessages(path, all, topics.cam0_topic, ros2::kImageType, dataset.frames[0].size());
  RequireMessages(path, all, topics.cam1_topic, ros2::kImageType, dataset.frames[1].size());
  dataset.image_bag = path;
  dataset.image_topics[0] = topics.cam0_topic;
  dataset.image_topics[1] = topics.cam1_topic;
  dataset.has_images = true;
  dataset.ros2_images = std::move(index);
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
  return DecodeImage(Where(r.reader->file(), r.topic, index), m);
}

struct Ros2StereoImageReader::Impl {
  std::shared_ptr<const Ros2ImageIndex> index;
  std::string topics[2];
  size_t file = 0;  ///< the file `fetcher` reads
  std::unique_ptr<ros2::MessageFetcher> fetcher;
};

Ros2StereoImageReader::Ros2StereoImageReader(const EurocDataset& dataset) : impl_(std::make_unique<Impl>()) {
  if (!dataset.ros2_images) throw DatasetError(dataset.root + ": not a ROS 2 recording read by ReadRos2Bag");
  impl_->index = dataset.ros2_images;
  for (int i = 0; i < 2; ++i) impl_->topics[i] = dataset.image_topics[i];
}

Ros2StereoImageReader::~Ros2StereoImageReader() = default;
Ros2StereoImageReader::Ros2StereoImageReader(Ros2StereoImageReader&&) noexcept = default;
Ros2StereoImageReader& Ros2StereoImageReader::operator=(Ros2StereoImageReader&&) noexcept = default;

cv::Mat Ros2StereoImageReader::Read(int camera, size_t index) {
  Impl& r = *impl_;
  const Ros2ImageIndex& images = *r.index;
  const std::string& topic = r.topics[camera];
  if (index >= images.images[camera].size()) {
    throw DatasetError(images.bag.path + ": " + topic + " has no message " + std::to_string(index));
  }
  const Ros2ImageIndex::Image& image = images.images[camera][index];
  if (!r.fetcher || r.file != image.place.file) {
    r.fetcher = nullptr;
    const std::string& file = images.bag.files[image.place.file];
    r.fetcher = images.bag.mcap ? ros2::OpenMcapFetcher(file) : ros2::OpenSqliteFetcher(file);
    r.file = image.place.file;
  }
  Message m;
  m.topic = &images.topics[image.topic];
  r.fetcher->Fetch(image.place, &m);
  return DecodeImage(Where(images.bag.files[image.place.file], topic, index), m);
}

}  // namespace vio::tools
