// Ros2StereoImageReader: the images of both cameras read at the places
// ReadRos2Bag found them, in any order and across several MCAP chunks (zstd,
// lz4, none), outside chunks and .db3 rows of one or several files (the
// latter two written by the independent writer of tools/ros2_testdata),
// equal the ASL folder's; a recording cut short after the first read is an
// error naming the file, not a crash.
#include <cstdlib>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "test_data.h"
#include "vio/dataset/ros2_dataset.h"

namespace vio::tools {
namespace {

constexpr Timestamp kStartNs = 1'403'715'274'302'142'976;
constexpr Timestamp kFrameNs = 50'000'000;
constexpr int kFrames = 24;

// Distinct per camera and frame; 640x480 (by default), so the frames span
// several 4 MB chunks.
cv::Mat FrameImage(int camera, int k, int rows = 480, int cols = 640) {
  cv::Mat image(rows, cols, CV_8UC1);
  for (int r = 0; r < image.rows; ++r) {
    for (int c = 0; c < image.cols; ++c) {
      image.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(r * 3 + c * (camera + 1) + 11 * k);
    }
  }
  return image;
}

EurocDataset WriteAsl(const std::string& root, int rows = 480, int cols = 640) {
  EurocDataset d;
  d.root = root;
  for (int i = 0; i < 10 * kFrames; ++i) {
    ImuSample s;
    s.t_ns = kStartNs + i * 5'000'000;
    s.accel_m_s2 = Eigen::Vector3d(0.0, 0.0, 9.81);
    d.imu.push_back(s);
  }
  for (int k = 0; k < kFrames; ++k) {
    for (int i = 0; i < 2; ++i) d.frames[i].push_back({kStartNs + k * kFrameNs, std::to_string(k) + ".png"});
  }
  WriteEuroc(d, root);
  for (int i = 0; i < 2; ++i) {
    const std::string folder = root + "/mav0/cam" + std::to_string(i) + "/data/";
    std::filesystem::create_directories(folder);
    for (int k = 0; k < kFrames; ++k) cv::imwrite(folder + std::to_string(k) + ".png", FrameImage(i, k, rows, cols));
  }
  return ReadEuroc(root);
}

void ExpectImages(const std::string& path, int rows = 480, int cols = 640) {
  SCOPED_TRACE(path);
  const EurocDataset bag = ReadRos2Bag(path, BagTopics{});
  ASSERT_EQ(bag.frames[0].size(), static_cast<size_t>(kFrames));
  Ros2StereoImageReader reader(bag);
  // Pairs forward, then single images backwards and jumping between chunks.
  for (int k = 0; k < kFrames; ++k) {
    for (int i = 0; i < 2; ++i) {
      EXPECT_EQ(cv::norm(reader.Read(i, k), FrameImage(i, k, rows, cols), cv::NORM_INF), 0.0) << i << k;
    }
  }
  for (int k : {23, 0, 12, 1, 22, 5, 5}) {
    const int i = k % 2;
    EXPECT_EQ(cv::norm(reader.Read(i, k), FrameImage(i, k, rows, cols), cv::NORM_INF), 0.0) << i << k;
  }
  EXPECT_THROW(reader.Read(0, kFrames), DatasetError);
}

TEST(Ros2Stereo, EveryStorageGivesTheAslImagesInAnyOrder) {
  const std::string dir = test::MakeTempDir("ros2_stereo");
  const EurocDataset asl = WriteAsl(dir + "/asl");
  for (const std::string compression : {"zstd", "lz4", "none"}) {
    const std::string path = dir + "/data_" + compression + ".mcap";
    WriteRos2Bag(asl, path, BagTopics{}, Ros2WriteOptions{"mcap", compression});
    ExpectImages(path);
  }
  WriteRos2Bag(asl, dir + "/data.db3", BagTopics{}, Ros2WriteOptions{});
  ExpectImages(dir + "/data.db3");
  WriteRos2Bag(asl, dir + "/folder", BagTopics{}, Ros2WriteOptions{"mcap", "zstd"});
  ExpectImages(dir + "/folder");
  EXPECT_GT(std::filesystem::file_size(dir + "/data_none.mcap"), std::uintmax_t{3} * (4 << 20));  // several chunks
}

// Runs a command of tools/ros2_testdata; fails the test when it fails.
void RunTool(const std::string& command, const std::string& log) {
  const int status = std::system(("cd " + test::SourceDir() + "/tools/ros2_testdata && " + command + " > " + log +
                                  " 2>&1").c_str());
  ASSERT_EQ(status, 0) << command << " (log: " << log << ")";
}

TEST(Ros2Stereo, MessagesOutsideChunksAndSeveralDb3FilesOfAnIndependentWriter) {
  if (std::system("node --version > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "node is not installed: tools/install_deps.sh test installs it";
  }
  ASSERT_TRUE(std::filesystem::is_directory(test::SourceDir() + "/tools/ros2_testdata/node_modules/@mcap/core"))
      << "tools/ros2_testdata has no node_modules: run tools/install_deps.sh test (npm ci there)";
  const std::string dir = test::MakeTempDir("ros2_stereo_foxglove");
  const EurocDataset asl = WriteAsl(dir + "/asl", 48, 64);
  for (const std::string compression : {"unchunked", "zstd"}) {
    const std::string out = dir + "/" + compression + ".mcap";
    RunTool("node write_bag.js --asl=" + asl.root + " --out=" + out + " --compression=" + compression, out + ".log");
    ExpectImages(out, 48, 64);
  }
  RunTool("node write_bag.js --format=jsonl --asl=" + asl.root + " --out=" + dir + "/messages.jsonl", dir + "/jsonl.log");
  RunTool("python3 write_db3.py " + dir + "/messages.jsonl " + dir + "/jazzy --layout=jazzy --files=3", dir + "/jazzy.log");
  ExpectImages(dir + "/jazzy", 48, 64);
}

TEST(Ros2Stereo, ARecordingCutShortAfterTheFirstReadIsAnError) {
  const std::string dir = test::MakeTempDir("ros2_stereo_cut");
  const std::string path = dir + "/data.mcap";
  WriteRos2Bag(WriteAsl(dir + "/asl"), path, BagTopics{}, Ros2WriteOptions{"mcap", "zstd"});
  const EurocDataset bag = ReadRos2Bag(path, BagTopics{});
  std::filesystem::resize_file(path, std::filesystem::file_size(path) / 2);
  Ros2StereoImageReader reader(bag);
  EXPECT_EQ(cv::norm(reader.Read(1, 0), FrameImage(1, 0), cv::NORM_INF), 0.0);
  try {
    reader.Read(0, kFrames - 1);
    ADD_FAILURE() << "no error";
  } catch (const DatasetError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("truncated or corrupt"), std::string::npos) << e.what();
  }
}

TEST(Ros2Stereo, ADatasetNotReadFromARecordingIsAnError) {
  EXPECT_THROW(Ros2StereoImageReader(EurocDataset{}), DatasetError);
}

}  // namespace
}  // namespace vio::tools
