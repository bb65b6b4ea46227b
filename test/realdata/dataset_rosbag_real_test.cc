// The real V1_01_easy_micro clip written as a ROS 1 bag reads back to the same
// frame stamps, IMU samples and images.
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "test_data.h"
#include "vio/dataset/rosbag_dataset.h"

namespace vio::tools {
namespace {

TEST(RosbagReal, MicroClipThroughABagIsUnchanged) {
  const std::string micro = test::EurocSequence("V1_01_easy_micro");
  VIO_REQUIRE_DATA(micro);
  const EurocDataset asl = ReadEuroc(micro);
  ASSERT_TRUE(asl.has_images);
  const std::string bag_path = test::MakeTempDir("rosbag_micro") + "/micro.bag";
  WriteBag(asl, bag_path, BagTopics{});
  const EurocDataset bag = ReadBag(bag_path, BagTopics{});
  ASSERT_EQ(bag.imu.size(), asl.imu.size());
  for (size_t i = 0; i < asl.imu.size(); ++i) {
    ASSERT_EQ(bag.imu[i].t_ns, asl.imu[i].t_ns) << i;
    ASSERT_EQ(bag.imu[i].gyro_rad_s, asl.imu[i].gyro_rad_s) << i;
    ASSERT_EQ(bag.imu[i].accel_m_s2, asl.imu[i].accel_m_s2) << i;
  }
  EXPECT_EQ(bag.groundtruth.size(), asl.groundtruth.size());
  for (int camera = 0; camera < 2; ++camera) {
    ASSERT_EQ(bag.frames[camera].size(), asl.frames[camera].size());
    BagImageReader reader(bag_path, bag.image_topics[camera]);
    for (size_t k = 0; k < asl.frames[camera].size(); ++k) {
      ASSERT_EQ(bag.frames[camera][k].t_ns, asl.frames[camera][k].t_ns);
      const cv::Mat original = cv::imread(micro + "/mav0/cam" + std::to_string(camera) + "/data/" +
                                              asl.frames[camera][k].filename,
                                          cv::IMREAD_GRAYSCALE);
      ASSERT_EQ(cv::norm(reader.Read(k), original, cv::NORM_INF), 0.0) << camera << " " << k;
    }
  }
}

}  // namespace
}  // namespace vio::tools
