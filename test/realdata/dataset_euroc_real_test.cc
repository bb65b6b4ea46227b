// The EuRoC readers on the real data of ../shared/data (skipped when absent):
// row counts from the data README, first and last rows checked exactly
// against the files, calibration against sensor.yaml, images that load.
#include <gtest/gtest.h>

#include <algorithm>
#include <optional>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "test_data.h"
#include "vio/dataset/euroc_dataset.h"
#include "vio/dataset/groundtruth_init.h"

namespace vio::tools {
namespace {

// The quaternion the reader returns for a file row (w, x, y, z): normalised.
Eigen::Quaterniond FileQuaternion(double w, double x, double y, double z) {
  return Eigen::Quaterniond(w, x, y, z).normalized();
}

void ExpectImu(const ImuSample& s, Timestamp t_ns, const Eigen::Vector3d& gyro,
               const Eigen::Vector3d& accel) {
  EXPECT_EQ(s.t_ns, t_ns);
  EXPECT_EQ(s.gyro_rad_s, gyro);
  EXPECT_EQ(s.accel_m_s2, accel);
}

TEST(EurocReal, V2_01_EasyRowsAndFirstLastValues) {
  const std::string root = test::EurocSequence("V2_01_easy");
  VIO_REQUIRE_DATA(root);
  const EurocDataset d = ReadEuroc(root);

  ASSERT_EQ(d.imu.size(), 22800u);
  ExpectImu(d.imu.front(), 1413393212225760512,
            {0.094945911308491532, 0.020245819323134219, 0.058643062867009467},
            {9.1283567083333317, 0.10623870833333333, -2.6069344583333329});
  ExpectImu(d.imu.back(), 1413393326220760576,
            {-0.0055850536063818549, 0.024434609527920613, 0.08307767239493008},
            {9.3571785416666664, 0.20430520833333332, -2.8194118749999997});
  EXPECT_EQ(d.imu_gaps.count, 0);

  ASSERT_EQ(d.groundtruth.size(), 22401u);
  const GroundTruthState& first = d.groundtruth.front();
  EXPECT_EQ(first.t_ns, 1413393213480760576);
  EXPECT_EQ(first.p_w_b, Eigen::Vector3d(-1.076119, 0.492468, 1.329941));
  EXPECT_EQ(first.q_w_b.coeffs(),
            FileQuaternion(0.606377, -0.005788, -0.795108, 0.008771).coeffs());
  EXPECT_EQ(first.v_w_b, Eigen::Vector3d(-0.033386, -0.000168, -0.005644));
  EXPECT_EQ(first.gyro_bias, Eigen::Vector3d(-0.002295, 0.024939, 0.081667));
  EXPECT_EQ(first.accel_bias, Eigen::Vector3d(-0.023601, 0.121044, 0.074783));
  const GroundTruthState& last = d.groundtruth.back();
  EXPECT_EQ(last.t_ns, 1413393325480760576);
  EXPECT_EQ(last.p_w_b, Eigen::Vector3d(-2.908331, -0.450494, 0.955040));
  EXPECT_EQ(last.q_w_b.coeffs(),
            FileQuaternion(0.470171, -0.487844, -0.641193, -0.360305).coeffs());
  EXPECT_EQ(last.v_w_b, Eigen::Vector3d(-0.004531, -0.000446, 0.004336));
  EXPECT_EQ(last.gyro_bias, Eigen::Vector3d(-0.002275, 0.024883, 0.081577));
  EXPECT_EQ(last.accel_bias, Eigen::Vector3d(-0.019635, 0.123542, 0.078490));

  for (int c = 0; c < 2; ++c) {
    ASSERT_EQ(d.frames[c].size(), 2280u);
    EXPECT_EQ(d.frames[c].front().t_ns, 1413393212255760384);
    EXPECT_EQ(d.frames[c].front().filename, "1413393212255760384.png");
    EXPECT_EQ(d.frames[c].back().t_ns, 1413393326205760512);
    EXPECT_EQ(d.frames[c].back().filename, "1413393326205760512.png");
  }
  EXPECT_FALSE(d.has_images);  // this sequence ships without its images
  EXPECT_TRUE(d.features.empty());
}

TEST(EurocReal, CalibrationMatchesSensorYaml) {
  const std::string root = test::EurocSequence("V2_01_easy");
  VIO_REQUIRE_DATA(root);
  EurocReadOptions options;
  options.read_imu = false;
  options.read_groundtruth = false;
  const EurocDataset d = ReadEuroc(root + "/mav0", options);
  EXPECT_TRUE(d.imu.empty());

  const CameraCalibration& cam0 = d.cameras[0];
  EXPECT_EQ(cam0.width, 752);
  EXPECT_EQ(cam0.height, 480);
  EXPECT_EQ(cam0.rate_hz, 20.0);
  EXPECT_EQ(cam0.intrinsics, Eigen::Vector4d(458.654, 457.296, 367.215, 248.375));
  EXPECT_EQ(cam0.distortion_model, "radial-tangential");
  EXPECT_EQ(cam0.distortion, Eigen::Vector4d(-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05));
  Eigen::Matrix4d T_b_c0;
  T_b_c0 << 0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,  //
      0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,            //
      -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949,        //
      0.0, 0.0, 0.0, 1.0;
  EXPECT_EQ(cam0.T_b_c.matrix(), T_b_c0);

  const CameraCalibration& cam1 = d.cameras[1];
  EXPECT_EQ(cam1.intrinsics, Eigen::Vector4d(457.587, 456.134, 379.999, 255.238));
  EXPECT_EQ(cam1.distortion,
            Eigen::Vector4d(-0.28368365, 0.07451284, -0.00010473, -3.55590700e-05));
  Eigen::Matrix4d T_b_c1;
  T_b_c1 << 0.0125552670891, -0.999755099723, 0.0182237714554, -0.0198435579556,  //
      0.999598781151, 0.0130119051815, 0.0251588363115, 0.0453689425024,          //
      -0.0253898008918, 0.0179005838253, 0.999517347078, 0.00786212447038,        //
      0.0, 0.0, 0.0, 1.0;
  EXPECT_EQ(cam1.T_b_c.matrix(), T_b_c1);

  const ImuCalibration imu = ReadImuYaml(root + "/mav0/imu0/sensor.yaml");
  EXPECT_EQ(imu.rate_hz, 200.0);
  EXPECT_EQ(imu.gyro_noise_density, 1.6968e-04);
  EXPECT_EQ(imu.gyro_random_walk, 1.9393e-05);
  EXPECT_EQ(imu.accel_noise_density, 2.0000e-3);
  EXPECT_EQ(imu.accel_random_walk, 3.0000e-3);
  EXPECT_EQ(imu.T_b_i.matrix(), Eigen::Matrix4d::Identity());
}

// Reading speed is measured by vio_bench (BM_ReadImuCsv), not asserted here.
TEST(EurocReal, ImuOfAWholeSequenceReadsEverySampleInOrder) {
  const std::string path = test::EurocSequence("V2_01_easy") + "/mav0/imu0/data.csv";
  VIO_REQUIRE_DATA(path);
  const std::vector<ImuSample> imu = ReadImuCsv(path);
  ASSERT_EQ(imu.size(), 22800u);
  for (size_t i = 1; i < imu.size(); ++i) ASSERT_GT(imu[i].t_ns, imu[i - 1].t_ns) << "sample " << i;
  EXPECT_EQ(FindImuGaps(imu, 200.0).count, 0);
}

// EuRoC's Vicon world has z up: summary.json may align these runs pos+yaw.
TEST(EurocReal, GroundTruthWorldsOfWholeSequencesAreGravityAligned) {
  for (const std::string name : {"V2_01_easy", "MH_04_difficult"}) {
    const std::string root = test::EurocSequence(name);
    VIO_REQUIRE_DATA(root);
    EurocReadOptions read;
    read.read_features = false;
    const EurocDataset d = ReadEuroc(root, read);
    const std::optional<double> tilt = GroundTruthTiltDeg(d.groundtruth, d.imu, 9.81);
    ASSERT_TRUE(tilt.has_value()) << name;
    EXPECT_LT(*tilt, kMaxPosYawTiltDeg) << name;
  }
}

TEST(EurocReal, V1_01_EasyMicroStereoImagesAndTumGroundTruth) {
  const std::string root = test::EurocSequence("V1_01_easy_micro");
  VIO_REQUIRE_DATA(root);
  const EurocDataset d = ReadEuroc(root);
  ASSERT_EQ(d.frames[0].size(), 95u);
  ASSERT_EQ(d.frames[1].size(), 95u);
  EXPECT_TRUE(d.has_images);
  for (int i = 0; i < 95; ++i) EXPECT_EQ(d.frames[0][i].t_ns, d.frames[1][i].t_ns);
  EXPECT_EQ(d.frames[0].front().filename, "1403715273262142976.png");
  EXPECT_EQ(d.frames[0].back().t_ns, 1403715277962142976);

  const cv::Mat image =
      cv::imread(root + "/mav0/cam1/data/" + d.frames[1][40].filename, cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(image.empty());
  EXPECT_EQ(image.cols, 752);
  EXPECT_EQ(image.rows, 480);
  EXPECT_EQ(image.type(), CV_8UC1);

  EXPECT_EQ(d.imu.size(), 29120u);
  ASSERT_EQ(d.groundtruth.size(), 28712u);  // TUM text: velocity and biases zero
  const GroundTruthState& first = d.groundtruth.front();
  EXPECT_EQ(first.t_ns, 1403715274302140000);
  EXPECT_EQ(first.p_w_b, Eigen::Vector3d(0.878612, 2.142470, 0.947262));
  EXPECT_EQ(first.q_w_b.coeffs(),
            FileQuaternion(0.060514, -0.828459, -0.058956, -0.553641).coeffs());
  EXPECT_EQ(first.v_w_b, Eigen::Vector3d::Zero());
  const GroundTruthState& last = d.groundtruth.back();
  EXPECT_EQ(last.t_ns, 1403715417857140000);
  EXPECT_EQ(last.p_w_b, Eigen::Vector3d(0.489592, 1.967734, 0.967288));
  EXPECT_EQ(last.q_w_b.coeffs(), FileQuaternion(0.154937, 0.780946, -0.241803, 0.554661).coeffs());
}

TEST(EurocReal, V1_01_EasyFlight10JpegPairs) {
  const std::string root = test::EurocSequence("V1_01_easy_flight10");
  VIO_REQUIRE_DATA(root);
  const EurocDataset d = ReadEuroc(root);
  ASSERT_EQ(d.frames[0].size(), 10u);
  ASSERT_EQ(d.frames[1].size(), 10u);
  EXPECT_TRUE(d.has_images);
  EXPECT_EQ(d.frames[0].front().filename, "1403715297312143104.jpg");
  EXPECT_EQ(d.frames[1].back().filename, "1403715297762142976.jpg");
  const cv::Mat image =
      cv::imread(root + "/mav0/cam0/data/" + d.frames[0][9].filename, cv::IMREAD_UNCHANGED);
  ASSERT_FALSE(image.empty());
  EXPECT_EQ(image.cols, 752);
  EXPECT_EQ(image.rows, 480);
  EXPECT_EQ(image.type(), CV_8UC1);
}

TEST(EurocReal, OtherSequencesRowCounts) {
  struct Expected {
    const char* name;
    std::size_t imu, groundtruth, frames;
  };
  for (const Expected& e : {Expected{"MH_04_difficult", 20320, 19753, 2033},
                            Expected{"V1_02_medium", 17100, 16702, 1710}}) {
    SCOPED_TRACE(e.name);
    const std::string root = test::EurocSequence(e.name);
    VIO_REQUIRE_DATA(root);
    const EurocDataset d = ReadEuroc(root);
    EXPECT_EQ(d.imu.size(), e.imu);
    EXPECT_EQ(d.groundtruth.size(), e.groundtruth);
    EXPECT_EQ(d.frames[0].size(), e.frames);
    EXPECT_EQ(d.frames[1].size(), e.frames);
    EXPECT_EQ(d.imu_gaps.count, 0);
  }
}

TEST(EurocReal, RealSequenceRoundTripsThroughWriter) {
  const std::string root = test::EurocSequence("V1_02_medium");
  VIO_REQUIRE_DATA(root);
  const EurocDataset original = ReadEuroc(root);
  const std::string copy = test::MakeTempDir("euroc_real_copy");
  WriteEuroc(original, copy);
  const EurocDataset again = ReadEuroc(copy);
  ASSERT_EQ(again.imu.size(), original.imu.size());
  for (std::size_t i = 0; i < original.imu.size(); ++i) {
    ASSERT_EQ(again.imu[i].t_ns, original.imu[i].t_ns);
    ASSERT_EQ(again.imu[i].gyro_rad_s, original.imu[i].gyro_rad_s);
    ASSERT_EQ(again.imu[i].accel_m_s2, original.imu[i].accel_m_s2);
  }
  ASSERT_EQ(again.groundtruth.size(), original.groundtruth.size());
  for (std::size_t i = 0; i < original.groundtruth.size(); ++i) {
    ASSERT_EQ(again.groundtruth[i].q_w_b.coeffs(), original.groundtruth[i].q_w_b.coeffs());
    ASSERT_EQ(again.groundtruth[i].p_w_b, original.groundtruth[i].p_w_b);
  }
  EXPECT_EQ(again.cameras[0].T_b_c.matrix(), original.cameras[0].T_b_c.matrix());
  EXPECT_EQ(again.cameras[1].distortion, original.cameras[1].distortion);
}

}  // namespace
}  // namespace vio::tools
