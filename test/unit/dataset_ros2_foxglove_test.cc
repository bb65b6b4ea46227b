// The ROS 2 readers against recordings an independent writer made:
// tools/ros2_testdata/write_bag.js (Foxglove's @mcap/core and
// @foxglove/rosmsg2-serialization, versions pinned by its package-lock.json)
// writes a small ASL folder as MCAP with every chunk compression (and
// without chunks), image
// encoding and ground-truth type, and as CDR that write_db3.py (python3's
// sqlite3) puts in rosbag2 .db3 folders of Humble's and Jazzy's layouts, one
// and three files. Each reads back to the folder's data exactly.
//
// Needs node and the packages `tools/install_deps.sh test` installs (npm ci in
// tools/ros2_testdata): without node the test skips, saying so; with node but
// without the packages it fails.
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
constexpr int kFrames = 4;

cv::Mat TestImage(int k) {
  cv::Mat image(40, 52, CV_8UC1);
  for (int r = 0; r < image.rows; ++r) {
    for (int c = 0; c < image.cols; ++c) image.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(r * c + 11 * k);
  }
  return image;
}

// An ASL folder with images (PNG, and a JPEG twin of each), IMU and ground truth.
EurocDataset WriteAsl(const std::string& root) {
  EurocDataset d;
  d.root = root;
  for (int i = 0; i < 20; ++i) {
    ImuSample s;
    s.t_ns = kStartNs - 7 + i * 5'000'000;
    s.gyro_rad_s = Eigen::Vector3d(0.1 * i, -0.2, 1e-9 * i);
    s.accel_m_s2 = Eigen::Vector3d(0.3, 9.81 + 1e-7 * i, -0.1 / 3);
    d.imu.push_back(s);
  }
  for (int k = 0; k < kFrames; ++k) {
    GroundTruthState g;
    g.t_ns = kStartNs + k * kFrameNs + 3;
    g.p_w_b = Eigen::Vector3d(k / 3.0, 2.0 * k, 0.5);
    g.q_w_b = Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * k, Eigen::Vector3d(1, 2, 3).normalized()));
    d.groundtruth.push_back(g);
    for (int i = 0; i < 2; ++i) d.frames[i].push_back({kStartNs + k * kFrameNs, std::to_string(k) + ".png"});
  }
  WriteEuroc(d, root);
  for (int i = 0; i < 2; ++i) {
    const std::string folder = root + "/mav0/cam" + std::to_string(i) + "/data/";
    std::filesystem::create_directories(folder);
    for (int k = 0; k < kFrames; ++k) {
      cv::imwrite(folder + std::to_string(k) + ".png", TestImage(k + 10 * i));
      cv::imwrite(folder + std::to_string(k) + ".jpg", TestImage(k + 10 * i));
    }
  }
  return ReadEuroc(root);
}

bool HaveNode() { return std::system("node --version > /dev/null 2>&1") == 0; }

// Runs a command of tools/ros2_testdata; fails the test when it fails.
void RunTool(const std::string& command, const std::string& log) {
  const int status = std::system(("cd " + test::SourceDir() + "/tools/ros2_testdata && " + command + " > " + log +
                                  " 2>&1").c_str());
  ASSERT_EQ(status, 0) << command << " (log: " << log << ")";
}

void ExpectSameData(const EurocDataset& asl, const std::string& path, bool jpeg) {
  SCOPED_TRACE(path);
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
  for (int i = 0; i < 2; ++i) {
    ASSERT_EQ(bag.frames[i].size(), asl.frames[i].size());
    Ros2ImageReader reader(path, bag.image_topics[i]);
    for (size_t k = 0; k < asl.frames[i].size(); ++k) {
      EXPECT_EQ(bag.frames[i][k].t_ns, asl.frames[i][k].t_ns);
      const std::string file = asl.root + "/mav0/cam" + std::to_string(i) + "/data/" + std::to_string(k) +
                               (jpeg ? ".jpg" : ".png");
      EXPECT_EQ(cv::norm(reader.Read(k), cv::imread(file, cv::IMREAD_GRAYSCALE), cv::NORM_INF), 0.0) << i << " " << k;
    }
  }
}

TEST(Ros2Foxglove, RecordingsOfAnIndependentWriterReadBackExactly) {
  if (!HaveNode()) GTEST_SKIP() << "node is not installed: tools/install_deps.sh test installs it";
  ASSERT_TRUE(std::filesystem::is_directory(test::SourceDir() + "/tools/ros2_testdata/node_modules/@mcap/core"))
      << "tools/ros2_testdata has no node_modules: run tools/install_deps.sh test (npm ci there)";
  const std::string dir = test::MakeTempDir("ros2_foxglove");
  const EurocDataset asl = WriteAsl(dir + "/asl");
  struct Variant {
    const char* compression;
    const char* image;
    const char* groundtruth;
  };
  const Variant variants[] = {{"none", "mono8", "pose"},     {"zstd", "rgb8", "transform"},
                              {"lz4", "bgra8", "odometry"},  {"zstd", "bgr8", "pose"},
                              {"lz4", "png", "transform"},   {"none", "jpeg", "odometry"},
                              {"unchunked", "mono8", "pose"}};
  for (const Variant& v : variants) {
    const std::string out = dir + "/" + v.compression + "_" + v.image + "_" + v.groundtruth + ".mcap";
    RunTool(std::string("node write_bag.js --asl=") + asl.root + " --out=" + out + " --compression=" + v.compression +
            " --image=" + v.image + " --groundtruth=" + v.groundtruth,
        out + ".log");
    ExpectSameData(asl, out, std::string(v.image) == "jpeg");
  }
  RunTool("node write_bag.js --format=jsonl --asl=" + asl.root + " --out=" + dir + "/messages.jsonl --image=rgb8 "
      "--groundtruth=odometry", dir + "/jsonl.log");
  RunTool("python3 write_db3.py " + dir + "/messages.jsonl " + dir + "/humble --layout=humble", dir + "/humble.log");
  ExpectSameData(asl, dir + "/humble", false);
  RunTool("python3 write_db3.py " + dir + "/messages.jsonl " + dir + "/jazzy --layout=jazzy --files=3", dir + "/jazzy.log");
  ExpectSameData(asl, dir + "/jazzy", false);
}

}  // namespace
}  // namespace vio::tools
