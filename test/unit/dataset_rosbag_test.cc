// ROS 1 bags without ROS: a small dataset written as a bag reads back to the
// same IMU samples, image stamps, images and ground truth; bad bags (missing
// topics, wrong types or encodings, unsorted or duplicated stamps, truncated
// files) are errors naming the bag, the topic and the message.
#include <filesystem>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <rosbag/bag.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>

#include "test_data.h"
#include "vio/dataset/rosbag_dataset.h"

namespace vio::tools {
namespace {

constexpr Timestamp kStartNs = 1'403'715'274'302'142'976;
constexpr Timestamp kFrameNs = 50'000'000;

cv::Mat TestImage(int k) {
  cv::Mat image(48, 64, CV_8UC1);
  for (int r = 0; r < image.rows; ++r) {
    for (int c = 0; c < image.cols; ++c) image.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(r * 3 + c + 7 * k);
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
    g.t_ns = kStartNs + k * kFrameNs;
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

TEST(Rosbag, AslToBagReadsBackTheSameData) {
  const std::string dir = test::MakeTempDir("rosbag_roundtrip");
  const EurocDataset asl = WriteSmallAsl(dir + "/asl");
  ASSERT_TRUE(asl.has_images);
  WriteBag(asl, dir + "/data.bag", BagTopics{});
  ASSERT_TRUE(IsBagPath(dir + "/data.bag"));
  EXPECT_FALSE(IsBagPath(dir + "/asl"));
  const EurocDataset bag = ReadBag(dir + "/data.bag", BagTopics{});
  ASSERT_EQ(bag.imu.size(), asl.imu.size());
  for (size_t i = 0; i < asl.imu.size(); ++i) {
    EXPECT_EQ(bag.imu[i].t_ns, asl.imu[i].t_ns);
    EXPECT_EQ(bag.imu[i].gyro_rad_s, asl.imu[i].gyro_rad_s);
    EXPECT_EQ(bag.imu[i].accel_m_s2, asl.imu[i].accel_m_s2);
  }
  ASSERT_EQ(bag.groundtruth.size(), asl.groundtruth.size());
  EXPECT_EQ(bag.groundtruth[3].t_ns, asl.groundtruth[3].t_ns);
  EXPECT_EQ(bag.groundtruth[3].p_w_b, asl.groundtruth[3].p_w_b);
  EXPECT_NEAR(bag.groundtruth[3].q_w_b.angularDistance(asl.groundtruth[3].q_w_b), 0.0, 1e-12);
  ASSERT_TRUE(bag.has_images);
  for (int i = 0; i < 2; ++i) {
    ASSERT_EQ(bag.frames[i].size(), 5u);
    BagImageReader reader(bag.image_bag, bag.image_topics[i]);
    for (size_t k : {0, 1, 4, 2}) {  // forward, then back (restarts)
      EXPECT_EQ(bag.frames[i][k].t_ns, asl.frames[i][k].t_ns);
      const cv::Mat image = reader.Read(k);
      EXPECT_EQ(cv::norm(image, TestImage(static_cast<int>(k) + 10 * i), cv::NORM_INF), 0.0) << i << " " << k;
    }
    EXPECT_THROW(reader.Read(5), DatasetError);
  }
  // And back to an ASL folder.
  EurocDataset with_calibration = bag;
  ApplyCalibrationFrom(dir + "/asl", &with_calibration);
  WriteAslFromBag(with_calibration, dir + "/back");
  const EurocDataset back = ReadEuroc(dir + "/back");
  ASSERT_TRUE(back.has_images);
  EXPECT_EQ(back.imu.size(), asl.imu.size());
  const cv::Mat last = cv::imread(dir + "/back/mav0/cam1/data/" + back.frames[1][4].filename, cv::IMREAD_GRAYSCALE);
  EXPECT_EQ(cv::norm(last, TestImage(14), cv::NORM_INF), 0.0);
}

void ExpectBagError(const std::string& path, const BagTopics& topics, const std::string& expected) {
  try {
    ReadBag(path, topics);
    ADD_FAILURE() << "read " << path;
  } catch (const DatasetError& e) {
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
  }
}

sensor_msgs::Image Image(Timestamp t_ns, const std::string& encoding) {
  sensor_msgs::Image msg;
  msg.header.stamp.fromNSec(static_cast<std::uint64_t>(t_ns));
  msg.width = 4;
  msg.height = 2;
  msg.step = encoding == "rgb8" ? 12 : 4;
  msg.encoding = encoding;
  msg.data.assign(msg.step * msg.height, 9);
  return msg;
}

sensor_msgs::Imu Imu(Timestamp t_ns) {
  sensor_msgs::Imu msg;
  msg.header.stamp.fromNSec(static_cast<std::uint64_t>(t_ns));
  return msg;
}

// One IMU message and images at `stamps` on both cameras (cam1 with `encoding`).
std::string WriteBadBag(const std::string& path, const std::vector<Timestamp>& stamps, const std::string& encoding) {
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  bag.write("/imu0", ros::Time(1), Imu(kStartNs));
  for (Timestamp t : stamps) {
    bag.write("/cam0/image_raw", ros::Time(2), Image(t, "mono8"));
    bag.write("/cam1/image_raw", ros::Time(2), Image(t, encoding));
  }
  return path;
}

TEST(Rosbag, BadBagsAreClearErrors) {
  const std::string dir = test::MakeTempDir("rosbag_bad");
  const std::vector<Timestamp> good = {kStartNs, kStartNs + kFrameNs};
  const std::string ok = WriteBadBag(dir + "/ok.bag", good, "mono8");
  EXPECT_EQ(ReadBag(ok, BagTopics{}).frames[1].size(), 2u);

  BagTopics missing;
  missing.cam1_topic = "/right/image";
  ExpectBagError(ok, missing, "no topic /right/image (sensor_msgs/Image); the bag has: ");
  BagTopics wrong_type;
  wrong_type.imu_topic = "/cam0/image_raw";
  ExpectBagError(ok, wrong_type, "topic /cam0/image_raw is sensor_msgs/Image, expected sensor_msgs/Imu");
  ExpectBagError(WriteBadBag(dir + "/rgb.bag", good, "rgb8"), BagTopics{},
                 "/cam1/image_raw message 0: image encoding 'rgb8', expected mono8");
  ExpectBagError(WriteBadBag(dir + "/dup.bag", {kStartNs, kStartNs}, "mono8"), BagTopics{},
                 "/cam0/image_raw message 1: stamp 1403715274302142976 duplicates the previous one");
  ExpectBagError(WriteBadBag(dir + "/back.bag", {kStartNs, kStartNs - 1}, "mono8"), BagTopics{},
                 "/cam0/image_raw message 1: stamp 1403715274302142975 is before the previous one");

  const std::string truncated = dir + "/truncated.bag";
  std::filesystem::copy_file(ok, truncated);
  std::filesystem::resize_file(truncated, std::filesystem::file_size(ok) / 2);
  ExpectBagError(truncated, BagTopics{}, "truncated.bag: cannot read the ROS bag");
}

}  // namespace
}  // namespace vio::tools
