// ROS 2 recordings without ROS: a small ASL folder written as MCAP (chunks
// uncompressed, zstd, lz4), as .db3 and as bag folders reads back to the same
// IMU samples, stamps, images and ground truth; damaged recordings (truncated,
// corrupt, unknown compression, missing topics, unusable encodings) are
// errors naming the file, the topic and the message, never crashes.
#include <filesystem>
#include <fstream>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "test_data.h"
#include "vio/dataset/ros2_dataset.h"

namespace vio::tools {
namespace {

constexpr Timestamp kStartNs = 1'403'715'274'302'142'976;
constexpr Timestamp kFrameNs = 50'000'000;

cv::Mat TestImage(int k) {
  cv::Mat image(48, 64, CV_8UC1);
  for (int r = 0; r < image.rows; ++r) {
    for (int c = 0; c < image.cols; ++c) image.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(r * 5 + c + 7 * k);
  }
  return image;
}

// An ASL folder with 5 stereo frames, 30 IMU samples and ground truth.
EurocDataset WriteSmallAsl(const std::string& root) {
  EurocDataset d;
  d.root = root;
  for (int i = 0; i < 30; ++i) {
    ImuSample s;
    s.t_ns = kStartNs + i * 5'000'000;
    s.gyro_rad_s = Eigen::Vector3d(0.1 * i, -0.2, 1e-9 * i);
    s.accel_m_s2 = Eigen::Vector3d(0.3, 9.81 + 1e-7 * i, -0.1);
    d.imu.push_back(s);
  }
  for (int k = 0; k < 5; ++k) {
    GroundTruthState g;
    g.t_ns = kStartNs + k * kFrameNs + 1;
    g.p_w_b = Eigen::Vector3d(k, 2.0 * k, 0.5);
    g.q_w_b = Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * k, Eigen::Vector3d::UnitZ()));
    d.groundtruth.push_back(g);
    for (int i = 0; i < 2; ++i) d.frames[i].push_back({kStartNs + k * kFrameNs, std::to_string(k) + ".png"});
  }
  WriteEuroc(d, root);
  for (int i = 0; i < 2; ++i) {
    const std::string folder = root + "/mav0/cam" + std::to_string(i) + "/data/";
    std::filesystem::create_directories(folder);
    for (int k = 0; k < 5; ++k) cv::imwrite(folder + std::to_string(k) + ".png", TestImage(k + 10 * i));
  }
  return ReadEuroc(root);
}

void ExpectSameData(const EurocDataset& asl, const std::string& path) {
  SCOPED_TRACE(path);
  ASSERT_TRUE(IsRos2BagPath(path));
  const EurocDataset bag = ReadRos2Bag(path, BagTopics{});
  ASSERT_EQ(bag.imu.size(), asl.imu.size());
  for (size_t i = 0; i < asl.imu.size(); ++i) {
    EXPECT_EQ(bag.imu[i].t_ns, asl.imu[i].t_ns);
    EXPECT_EQ(bag.imu[i].gyro_rad_s, asl.imu[i].gyro_rad_s);
    EXPECT_EQ(bag.imu[i].accel_m_s2, asl.imu[i].accel_m_s2);
  }
  ASSERT_EQ(bag.groundtruth.size(), asl.groundtruth.size());
  for (size_t i = 0; i < asl.groundtruth.size(); ++i) {
    EXPECT_EQ(bag.groundtruth[i].t_ns, asl.groundtruth[i].t_ns);
    EXPECT_EQ(bag.groundtruth[i].p_w_b, asl.groundtruth[i].p_w_b);
    EXPECT_NEAR(bag.groundtruth[i].q_w_b.angularDistance(asl.groundtruth[i].q_w_b), 0.0, 1e-12);
  }
  ASSERT_TRUE(bag.has_images);
  for (int i = 0; i < 2; ++i) {
    ASSERT_EQ(bag.frames[i].size(), 5u);
    Ros2ImageReader reader(bag.image_bag, bag.image_topics[i]);
    for (size_t k : {0, 1, 4, 2}) {  // forward, then back (restarts)
      EXPECT_EQ(bag.frames[i][k].t_ns, asl.frames[i][k].t_ns);
      EXPECT_EQ(cv::norm(reader.Read(k), TestImage(static_cast<int>(k) + 10 * i), cv::NORM_INF), 0.0) << i << k;
    }
    EXPECT_THROW(reader.Read(5), DatasetError);
  }
}

TEST(Ros2, AslToEveryStorageReadsBackTheSameData) {
  const std::string dir = test::MakeTempDir("ros2_roundtrip");
  const EurocDataset asl = WriteSmallAsl(dir + "/asl");
  EXPECT_FALSE(IsRos2BagPath(dir + "/asl"));
  for (const std::string compression : {"zstd", "lz4", "none"}) {
    const std::string path = dir + "/data_" + compression + ".mcap";
    WriteRos2Bag(asl, path, BagTopics{}, Ros2WriteOptions{"mcap", compression});
    ExpectSameData(asl, path);
  }
  WriteRos2Bag(asl, dir + "/data.db3", BagTopics{}, Ros2WriteOptions{});
  ExpectSameData(asl, dir + "/data.db3");
  for (const std::string storage : {"mcap", "sqlite3"}) {
    WriteRos2Bag(asl, dir + "/folder_" + storage, BagTopics{}, Ros2WriteOptions{storage, "zstd"});
    ExpectSameData(asl, dir + "/folder_" + storage);
  }
  EXPECT_TRUE(std::filesystem::exists(dir + "/folder_sqlite3/folder_sqlite3_0.db3"));

  // And back to an ASL folder.
  EurocDataset bag = ReadRos2Bag(dir + "/folder_mcap", BagTopics{});
  ApplyCalibrationFrom(dir + "/asl", &bag);
  WriteAslFromBag(bag, dir + "/back");
  const EurocDataset back = ReadEuroc(dir + "/back");
  ASSERT_TRUE(back.has_images);
  EXPECT_EQ(back.imu.size(), asl.imu.size());
  const cv::Mat last = cv::imread(dir + "/back/mav0/cam1/data/" + back.frames[1][4].filename, cv::IMREAD_GRAYSCALE);
  EXPECT_EQ(cv::norm(last, TestImage(14), cv::NORM_INF), 0.0);
}

std::string ErrorOf(const std::string& path, const BagTopics& topics = {}) {
  try {
    const EurocDataset d = ReadRos2Bag(path, topics);
    for (int i = 0; i < 2; ++i) {
      Ros2ImageReader reader(path, d.image_topics[i]);
      for (size_t k = 0; k < d.frames[i].size(); ++k) reader.Read(k);
    }
  } catch (const DatasetError& e) {
    return e.what();
  }
  return "no error";
}

#define EXPECT_HAS(text, part) EXPECT_NE(std::string(text).find(part), std::string::npos) << (text)

std::string ReadAll(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void WriteAll(const std::string& path, const std::string& bytes) { std::ofstream(path, std::ios::binary) << bytes; }

// `bytes` with every `from` replaced by `to`.
std::string Replaced(std::string bytes, const std::string& from, const std::string& to) {
  for (size_t at = bytes.find(from); at != std::string::npos; at = bytes.find(from, at + to.size())) {
    bytes.replace(at, from.size(), to);
  }
  return bytes;
}

// A copy of `path` with every `from` replaced by `to` (same length).
std::string Patched(const std::string& path, const std::string& copy, const std::string& from, const std::string& to) {
  WriteAll(copy, Replaced(ReadAll(path), from, to));
  return copy;
}

TEST(Ros2, BadRecordingsAreClearErrors) {
  const std::string dir = test::MakeTempDir("ros2_bad");
  const EurocDataset asl = WriteSmallAsl(dir + "/asl");
  const std::string zstd = dir + "/ok.mcap", plain = dir + "/plain.mcap", db3 = dir + "/ok.db3";
  WriteRos2Bag(asl, zstd, BagTopics{}, Ros2WriteOptions{"mcap", "zstd"});
  WriteRos2Bag(asl, plain, BagTopics{}, Ros2WriteOptions{"mcap", "none"});
  WriteRos2Bag(asl, db3, BagTopics{}, Ros2WriteOptions{});
  EXPECT_EQ(ErrorOf(zstd), "no error");

  BagTopics missing;
  missing.cam1_topic = "/right/image";
  for (const std::string& path : {zstd, db3}) {
    const std::string e = ErrorOf(path, missing);
    EXPECT_HAS(e, path + ": no topic /right/image (sensor_msgs/msg/Image); the recording has: ");
    EXPECT_HAS(e, "/imu0 (sensor_msgs/msg/Imu)");
    EXPECT_HAS(e, "/cam0/image_raw (sensor_msgs/msg/Image)");
  }
  BagTopics wrong_type;
  wrong_type.imu_topic = "/cam0/image_raw";
  EXPECT_HAS(ErrorOf(zstd, wrong_type), "/cam0/image_raw message 0: topic /cam0/image_raw is sensor_msgs/msg/Image, "
                                        "expected sensor_msgs/msg/Imu");
  // sqlite3 has no checksums: an encoding patched in the file reaches the decoder.
  EXPECT_HAS(ErrorOf(Patched(db3, dir + "/mono9.db3", "mono8", "mono9")),
             "mono9.db3: /cam0/image_raw message 0: image encoding 'mono9' cannot be used");
  EXPECT_HAS(ErrorOf(Patched(zstd, dir + "/bz2.mcap", std::string("\4\0\0\0zstd", 8), std::string("\4\0\0\0zstx", 8))),
             "bz2.mcap: a chunk is compressed with 'zstx', which this reader does not know");

  // Cut anywhere in the data, or a byte flipped in a chunk: an error naming the file.
  for (const std::string& path : {zstd, plain}) {
    const std::string bytes = ReadAll(path);
    for (size_t size : {size_t{5}, size_t{9}, size_t{30}, bytes.size() / 3, bytes.size() / 2, bytes.size() - 60}) {
      WriteAll(dir + "/cut.mcap", bytes.substr(0, size));
      EXPECT_HAS(ErrorOf(dir + "/cut.mcap"), dir + "/cut.mcap: ");
    }
    std::string flipped = bytes;
    flipped[bytes.size() - 100] = static_cast<char>(flipped[bytes.size() - 100] ^ 0x5a);  // in the last chunk
    WriteAll(dir + "/flipped.mcap", flipped);
    EXPECT_HAS(ErrorOf(dir + "/flipped.mcap"), "truncated or corrupt MCAP file");
  }
  const std::string bytes = ReadAll(db3);
  WriteAll(dir + "/cut.db3", bytes.substr(0, bytes.size() / 2));
  EXPECT_HAS(ErrorOf(dir + "/cut.db3"), dir + "/cut.db3: ");
  WriteAll(dir + "/text.db3", "not a database at all, just some text that is long enough to be read as a header");
  EXPECT_HAS(ErrorOf(dir + "/text.db3"), "not a rosbag2 sqlite3 file");
  WriteAll(dir + "/text.mcap", "not an mcap");
  EXPECT_HAS(ErrorOf(dir + "/text.mcap"), "text.mcap: not an MCAP file");

  // Bag folders: metadata naming a missing file, or rosbag2's file compression.
  WriteRos2Bag(asl, dir + "/folder", BagTopics{}, Ros2WriteOptions{"sqlite3", "zstd"});
  const std::string metadata = ReadAll(dir + "/folder/metadata.yaml");
  WriteAll(dir + "/folder/metadata.yaml", Replaced(metadata, "folder_0", "other_0"));
  EXPECT_HAS(ErrorOf(dir + "/folder"), "metadata.yaml: its file other_0.db3 is not in");
  WriteAll(dir + "/folder/metadata.yaml", Replaced(metadata, "compression_format: \"\"", "compression_format: zstd"));
  EXPECT_HAS(ErrorOf(dir + "/folder"), "metadata.yaml: the bag is compressed with zstd");
  EXPECT_THROW(WriteRos2Bag(asl, dir + "/x.mcap", BagTopics{}, Ros2WriteOptions{"mcap", "bz2"}), DatasetError);
}

}  // namespace
}  // namespace vio::tools
