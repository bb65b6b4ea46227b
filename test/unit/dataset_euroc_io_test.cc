// EuRoC ASL I/O on synthetic data: WriteEuroc then ReadEuroc gives every
// field back bit-exactly; real-world quirks (CRLF, '#' headers, `%YAML:1.0`,
// blank trailing lines, TUM decimal seconds) parse; FindImuGaps counts.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <opencv2/core.hpp>
#include <string>

#include "test_data.h"
#include "vio/dataset/euroc_dataset.h"

namespace vio::tools {
namespace {

using ::testing::HasSubstr;

constexpr Timestamp kImuPeriodNs = 5'000'000;  // 200 Hz

void WriteFile(const std::string& path, const std::string& content) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream(path, std::ios::binary) << content;
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Values with full 17-digit mantissas, so a lossy writer would be caught.
double Awkward(int i, double scale) { return scale * std::sin(0.7 * i + 0.1) / 3.0; }

Eigen::Isometry3d AwkwardPose(double angle, const Eigen::Vector3d& p) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() =
      Eigen::AngleAxisd(angle, Eigen::Vector3d(1.0, -2.0, 0.5).normalized()).toRotationMatrix();
  T.translation() = p;
  return T;
}

EurocDataset MakeSyntheticDataset() {
  EurocDataset d;
  d.imu_calibration.rate_hz = 200.0;
  d.imu_calibration.gyro_noise_density = 1.0 / 3.0 * 1e-4;
  d.imu_calibration.gyro_random_walk = 2.0 / 7.0 * 1e-5;
  d.imu_calibration.accel_noise_density = 1.0 / 9.0 * 1e-2;
  d.imu_calibration.accel_random_walk = 3.0 / 11.0 * 1e-3;
  d.imu_calibration.T_b_i = AwkwardPose(0.01, {1e-3 / 3.0, 0.0, -2e-3 / 7.0});
  for (int i = 0; i < 40; ++i) {
    ImuSample s;
    s.t_ns = 1403715273262142976 + i * kImuPeriodNs + (i % 3);
    s.gyro_rad_s = {Awkward(i, 0.1), Awkward(i + 1, -0.2), Awkward(i + 2, 1e-7)};
    s.accel_m_s2 = {9.81 + Awkward(i, 1.0), Awkward(i + 3, 0.5), Awkward(i + 4, -3.7e5)};
    d.imu.push_back(s);
  }
  for (int c = 0; c < 2; ++c) {
    CameraCalibration& cam = d.cameras[c];
    cam.width = 640 + c;
    cam.height = 480 - c;
    cam.rate_hz = 20.0 / 3.0;
    cam.intrinsics = {458.654 + 1.0 / 3.0, 457.296, 367.215 / 7.0, 248.375 + c};
    cam.distortion_model = c == 0 ? "radial-tangential" : "equidistant";
    cam.distortion = {-0.28340811 / 3.0, 0.07395907, -0.00019359, 1.76187114e-05 / 7.0};
    cam.T_b_c =
        AwkwardPose(1.5 + 0.1 * c, {-0.0216401454975, -0.064676986768 + 0.11 * c, 1.0 / 3.0});
    for (int i = 0; i < 5; ++i) {
      const Timestamp t_ns = 1403715273262142976 + i * 50'000'000;
      d.frames[c].push_back({t_ns, std::to_string(t_ns) + (c == 0 ? ".png" : ".jpg")});
    }
  }
  for (int i = 0; i < 12; ++i) {
    GroundTruthState gt;
    gt.t_ns = 1403715273262142976 + i * kImuPeriodNs;
    gt.p_w_b = {Awkward(i, 3.0), Awkward(i + 1, -1.0), Awkward(i + 2, 1e-9)};
    gt.q_w_b = Eigen::Quaterniond(
        Eigen::AngleAxisd(0.3 * i + 0.01, Eigen::Vector3d(0.2, 1, -0.4).normalized()));
    gt.v_w_b = {Awkward(i, 0.3), Awkward(i + 5, 0.4), Awkward(i + 6, -0.5)};
    gt.gyro_bias = {Awkward(i, 1e-3), Awkward(i + 7, 2e-3), Awkward(i + 8, 3e-3)};
    gt.accel_bias = {Awkward(i, 1e-1), Awkward(i + 9, 2e-1), Awkward(i + 10, 3e-1)};
    d.groundtruth.push_back(gt);
  }
  for (int i = 0; i < 3; ++i) {
    for (int c = 0; c < 2; ++c) {
      for (std::int64_t id : {std::int64_t{4}, std::int64_t{17}, std::int64_t{1} << 40}) {
        d.features.push_back({d.frames[c][i].t_ns, c, id, {Awkward(i, 752.0), Awkward(c, 480.0)}});
      }
    }
  }
  return d;
}

void ExpectSameImu(const std::vector<ImuSample>& a, const std::vector<ImuSample>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].t_ns, b[i].t_ns);
    EXPECT_EQ(a[i].gyro_rad_s, b[i].gyro_rad_s) << "row " << i;
    EXPECT_EQ(a[i].accel_m_s2, b[i].accel_m_s2) << "row " << i;
  }
}

void ExpectSameCamera(const CameraCalibration& a, const CameraCalibration& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  EXPECT_EQ(a.rate_hz, b.rate_hz);
  EXPECT_EQ(a.intrinsics, b.intrinsics);
  EXPECT_EQ(a.distortion_model, b.distortion_model);
  EXPECT_EQ(a.distortion, b.distortion);
  EXPECT_EQ(a.T_b_c.matrix(), b.T_b_c.matrix());
}

void ExpectSameImuCalibration(const ImuCalibration& a, const ImuCalibration& b) {
  EXPECT_EQ(a.rate_hz, b.rate_hz);
  EXPECT_EQ(a.gyro_noise_density, b.gyro_noise_density);
  EXPECT_EQ(a.gyro_random_walk, b.gyro_random_walk);
  EXPECT_EQ(a.accel_noise_density, b.accel_noise_density);
  EXPECT_EQ(a.accel_random_walk, b.accel_random_walk);
  EXPECT_EQ(a.T_b_i.matrix(), b.T_b_i.matrix());
}

void ExpectSameGroundTruth(const std::vector<GroundTruthState>& a,
                           const std::vector<GroundTruthState>& b, bool with_velocity_and_biases) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    SCOPED_TRACE("ground truth row " + std::to_string(i));
    EXPECT_EQ(a[i].t_ns, b[i].t_ns);
    EXPECT_EQ(a[i].p_w_b, b[i].p_w_b);
    EXPECT_EQ(a[i].q_w_b.coeffs(), b[i].q_w_b.coeffs());
    if (!with_velocity_and_biases) continue;
    EXPECT_EQ(a[i].v_w_b, b[i].v_w_b);
    EXPECT_EQ(a[i].gyro_bias, b[i].gyro_bias);
    EXPECT_EQ(a[i].accel_bias, b[i].accel_bias);
  }
}

void ExpectSameFeatures(const std::vector<FeatureObservation>& a,
                        const std::vector<FeatureObservation>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].t_ns, b[i].t_ns);
    EXPECT_EQ(a[i].camera, b[i].camera);
    EXPECT_EQ(a[i].feature_id, b[i].feature_id);
    EXPECT_EQ(a[i].uv_px, b[i].uv_px);
  }
}

TEST(EurocIo, WriteThenReadGivesEveryFieldBackExactly) {
  const EurocDataset written = MakeSyntheticDataset();
  const std::string root = test::MakeTempDir("euroc_roundtrip");
  WriteEuroc(written, root);
  const EurocDataset read = ReadEuroc(root);

  EXPECT_EQ(read.root, root);
  ExpectSameImuCalibration(read.imu_calibration, written.imu_calibration);
  ExpectSameImu(read.imu, written.imu);
  EXPECT_EQ(read.imu_gaps.count, 0);
  for (int c = 0; c < 2; ++c) {
    SCOPED_TRACE("camera " + std::to_string(c));
    ExpectSameCamera(read.cameras[c], written.cameras[c]);
    ASSERT_EQ(read.frames[c].size(), written.frames[c].size());
    for (std::size_t i = 0; i < read.frames[c].size(); ++i) {
      EXPECT_EQ(read.frames[c][i].t_ns, written.frames[c][i].t_ns);
      EXPECT_EQ(read.frames[c][i].filename, written.frames[c][i].filename);
    }
    EXPECT_TRUE(std::filesystem::is_directory(root + "/mav0/cam" + std::to_string(c) + "/data"));
  }
  EXPECT_FALSE(read.has_images);  // camN/data/ is empty: no images to check
  ExpectSameGroundTruth(read.groundtruth, written.groundtruth, /*with_velocity_and_biases=*/true);
  ExpectSameFeatures(read.features, written.features);
  EXPECT_TRUE(std::filesystem::exists(root + "/mav0/body.yaml"));
}

TEST(EurocIo, OutputIsDeterministic) {
  const EurocDataset dataset = MakeSyntheticDataset();
  const std::string a = test::MakeTempDir("euroc_det_a");
  const std::string b = test::MakeTempDir("euroc_det_b");
  WriteEuroc(dataset, a);
  WriteEuroc(dataset, b);
  for (const char* file :
       {"imu0/data.csv", "imu0/sensor.yaml", "cam0/data.csv", "cam1/sensor.yaml",
        "state_groundtruth_estimate0/data.csv", "features0/data.csv", "body.yaml"}) {
    SCOPED_TRACE(file);
    const std::string text = ReadFile(a + "/mav0/" + file);
    EXPECT_FALSE(text.empty());
    EXPECT_EQ(text, ReadFile(b + "/mav0/" + file));
  }
}

TEST(EurocIo, ReadsMav0FolderItselfAndDropsStaleOptionalParts) {
  EurocDataset dataset = MakeSyntheticDataset();
  const std::string root = test::MakeTempDir("euroc_mav0");
  WriteEuroc(dataset, root);
  dataset.features.clear();
  dataset.groundtruth.clear();
  WriteEuroc(dataset, root + "/");
  const EurocDataset read = ReadEuroc(root + "/mav0");
  EXPECT_EQ(read.root, root);
  EXPECT_EQ(read.imu.size(), dataset.imu.size());
  EXPECT_TRUE(read.groundtruth.empty());
  EXPECT_TRUE(read.features.empty());
}

TEST(EurocIo, ReadOptionsLeaveUnrequestedPartsEmpty) {
  const std::string root = test::MakeTempDir("euroc_options");
  WriteEuroc(MakeSyntheticDataset(), root);
  EurocReadOptions options;
  options.read_imu = false;
  options.read_groundtruth = false;
  options.read_features = false;
  const EurocDataset read = ReadEuroc(root, options);
  EXPECT_TRUE(read.imu.empty());
  EXPECT_TRUE(read.groundtruth.empty());
  EXPECT_TRUE(read.features.empty());
  EXPECT_EQ(read.frames[0].size(), 5u);
}

TEST(EurocIo, ImagesAreCheckedOnceAnyImageIsPresent) {
  EurocDataset dataset = MakeSyntheticDataset();
  const std::string root = test::MakeTempDir("euroc_images");
  WriteEuroc(dataset, root);
  for (int c = 0; c < 2; ++c) {
    for (const CameraFrame& frame : dataset.frames[c]) {
      WriteFile(root + "/mav0/cam" + std::to_string(c) + "/data/" + frame.filename, "img");
    }
  }
  EXPECT_TRUE(ReadEuroc(root).has_images);

  const std::string missing = root + "/mav0/cam1/data/" + dataset.frames[1][2].filename;
  std::filesystem::remove(missing);
  std::filesystem::remove(root + "/mav0/cam1/data/" + dataset.frames[1][3].filename);
  try {
    ReadEuroc(root);
    ADD_FAILURE() << "a missing listed image was not reported";
  } catch (const DatasetError& e) {
    // Line 4: header, then rows 0..2; the first missing file is named.
    EXPECT_THAT(e.what(), HasSubstr("cam1/data.csv:4: listed image missing: " + missing));
  }
  EurocReadOptions no_check;
  no_check.check_images = false;
  EXPECT_FALSE(ReadEuroc(root, no_check).has_images);
}

TEST(EurocIo, CrlfCommentsAndBlankTrailingLinesParse) {
  const std::string dir = test::MakeTempDir("euroc_crlf");
  WriteFile(
      dir + "/imu.csv",
      "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
      "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\r\n"
      "1413393212225760512,0.094945911308491532,0.020245819323134219,0.058643062867009467,"
      "9.1283567083333317,0.10623870833333333,-2.6069344583333329\r\n"
      "# a comment line in the middle\r\n"
      "1413393212230760448, 0.058643062867009467 ,3.5e-2,-0,9,+1.1604535833333331,-2.623278875\r\n"
      "\r\n\r\n");
  const std::vector<ImuSample> imu = ReadImuCsv(dir + "/imu.csv");
  ASSERT_EQ(imu.size(), 2u);
  EXPECT_EQ(imu[0].t_ns, 1413393212225760512);
  EXPECT_EQ(imu[0].gyro_rad_s,
            Eigen::Vector3d(0.094945911308491532, 0.020245819323134219, 0.058643062867009467));
  EXPECT_EQ(imu[0].accel_m_s2,
            Eigen::Vector3d(9.1283567083333317, 0.10623870833333333, -2.6069344583333329));
  EXPECT_EQ(imu[1].t_ns,
            1413393212230760448);  // not representable as a double: parsed as an integer
  EXPECT_EQ(imu[1].gyro_rad_s, Eigen::Vector3d(0.058643062867009467, 0.035, 0.0));
  EXPECT_TRUE(std::signbit(imu[1].gyro_rad_s.z()));
  EXPECT_EQ(imu[1].accel_m_s2, Eigen::Vector3d(9.0, 1.1604535833333331, -2.623278875));
}

TEST(EurocIo, TumTrajectoryDecimalSecondsAreExact) {
  const std::string dir = test::MakeTempDir("euroc_tum");
  WriteFile(dir + "/gt.txt",
            "# timestamp(s) tx ty tz qx qy qz qw\r\n"
            "1403715274.30214 0.878612 2.142470 0.947262 -0.828459 -0.058956 -0.553641 0.060514\r\n"
            "1403715274.3071400005\t0.878658  2.142398 0.947252 0 0 0 1\n"
            "1403715275 0 0 0 0 0 0 1\n");
  const std::vector<GroundTruthState> poses = ReadTumTrajectory(dir + "/gt.txt");
  ASSERT_EQ(poses.size(), 3u);
  EXPECT_EQ(poses[0].t_ns, 1403715274302140000);
  EXPECT_EQ(poses[1].t_ns, 1403715274307140001);  // 10th fraction digit rounds half up
  EXPECT_EQ(poses[2].t_ns, 1403715275000000000);
  EXPECT_EQ(poses[0].p_w_b, Eigen::Vector3d(0.878612, 2.142470, 0.947262));
  const Eigen::Quaterniond q0 =
      Eigen::Quaterniond(0.060514, -0.828459, -0.058956, -0.553641).normalized();
  EXPECT_EQ(poses[0].q_w_b.coeffs(), q0.coeffs());
  EXPECT_EQ(poses[1].q_w_b.coeffs(), Eigen::Quaterniond::Identity().coeffs());
  EXPECT_EQ(poses[1].v_w_b, Eigen::Vector3d::Zero());

  const std::vector<GroundTruthState> written = MakeSyntheticDataset().groundtruth;
  WriteTumTrajectory(written, dir + "/out.txt");
  ExpectSameGroundTruth(ReadTumTrajectory(dir + "/out.txt"), written,
                        /*with_velocity_and_biases=*/false);
}

TEST(EurocIo, SingleFileWritersRoundTrip) {
  const std::string dir = test::MakeTempDir("euroc_single");
  const EurocDataset d = MakeSyntheticDataset();
  WriteImuCsv(d.imu, dir + "/imu.csv");
  ExpectSameImu(ReadImuCsv(dir + "/imu.csv"), d.imu);
  WriteGroundTruthCsv(d.groundtruth, dir + "/gt.csv");
  ExpectSameGroundTruth(ReadGroundTruthCsv(dir + "/gt.csv"), d.groundtruth, true);
  std::vector<FeatureObservation> shuffled(d.features.rbegin(), d.features.rend());
  WriteFeaturesCsv(shuffled, dir + "/features.csv");
  ExpectSameFeatures(ReadFeaturesCsv(dir + "/features.csv"), d.features);  // sorted on write
  WriteFeaturesCsv({}, dir + "/empty_features.csv");
  EXPECT_TRUE(ReadFeaturesCsv(dir + "/empty_features.csv").empty());
  WriteCameraYaml(d.cameras[1], dir + "/cam.yaml");
  ExpectSameCamera(ReadCameraYaml(dir + "/cam.yaml"), d.cameras[1]);
  WriteImuYaml(d.imu_calibration, dir + "/imu.yaml");
  ExpectSameImuCalibration(ReadImuYaml(dir + "/imu.yaml"), d.imu_calibration);
}

// vio run streams features0 one timestamp at a time: the groups are the
// whole table's rows, in order, and ReadEuroc with stream_features keeps none.
TEST(EurocIo, FeatureStreamGivesTheTableOneTimestampAtATime) {
  const EurocDataset written = MakeSyntheticDataset();
  const std::string root = test::MakeTempDir("euroc_feature_stream");
  WriteEuroc(written, root);
  FeatureCsvStream stream(root + "/mav0/features0/data.csv");
  std::vector<FeatureObservation> streamed, group;
  int groups = 0;
  while (stream.Next(&group)) {
    ASSERT_FALSE(group.empty());
    for (const FeatureObservation& f : group) EXPECT_EQ(f.t_ns, group.front().t_ns);
    EXPECT_TRUE(streamed.empty() || streamed.back().t_ns < group.front().t_ns);
    streamed.insert(streamed.end(), group.begin(), group.end());
    ++groups;
  }
  EXPECT_GT(groups, 1);
  ExpectSameFeatures(streamed, written.features);

  EurocReadOptions options;
  options.stream_features = true;
  const EurocDataset read = ReadEuroc(root, options);
  EXPECT_TRUE(read.features.empty());
  EXPECT_EQ(read.features_file, root + "/mav0/features0/data.csv");
}

TEST(EurocIo, FeaturesReaderSortsRowsOfOneTimestamp) {
  const std::string dir = test::MakeTempDir("euroc_features");
  WriteFile(dir + "/f.csv",
            "#timestamp [ns],camera,feature_id,u [px],v [px]\n"
            "10,1,3,1.5,2.5\n10,0,9,3,4\n10,0,2,5,6\n20,0,1,7,8\n");
  const std::vector<FeatureObservation> f = ReadFeaturesCsv(dir + "/f.csv");
  ASSERT_EQ(f.size(), 4u);
  EXPECT_EQ(f[0].feature_id, 2);
  EXPECT_EQ(f[1].feature_id, 9);
  EXPECT_EQ(f[2].camera, 1);
  EXPECT_EQ(f[2].uv_px, Eigen::Vector2d(1.5, 2.5));
  EXPECT_EQ(f[3].t_ns, 20);
}

constexpr const char* kRealCam0Yaml =
    "%YAML:1.0\r\n"
    "# General sensor definitions.\r\n"
    "sensor_type: camera\r\n"
    "comment: VI-Sensor cam0 (MT9M034)\r\n"
    "\r\n"
    "# Sensor extrinsics wrt. the body-frame.\r\n"
    "T_BS:\r\n"
    "  cols: 4\r\n"
    "  rows: 4\r\n"
    "  data: [0.0148655429818, -0.999880929698, 0.00414029679422, -0.0216401454975,\r\n"
    "         0.999557249008, 0.0149672133247, 0.025715529948, -0.064676986768,\r\n"
    "        -0.0257744366974, 0.00375618835797, 0.999660727178, 0.00981073058949,\r\n"
    "         0.0, 0.0, 0.0, 1.0]\r\n"
    "\r\n"
    "# Camera specific definitions.\r\n"
    "rate_hz: 20\r\n"
    "resolution: [752, 480]\r\n"
    "camera_model: pinhole\r\n"
    "intrinsics: [458.654, 457.296, 367.215, 248.375] #fu, fv, cu, cv\r\n"
    "distortion_model: radial-tangential\r\n"
    "distortion_coefficients: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]\r\n";

TEST(EurocIo, OpenCvStyleSensorYamlParses) {
  const std::string dir = test::MakeTempDir("euroc_yaml");
  WriteFile(dir + "/sensor.yaml", kRealCam0Yaml);
  const CameraCalibration cam = ReadCameraYaml(dir + "/sensor.yaml");
  EXPECT_EQ(cam.width, 752);
  EXPECT_EQ(cam.height, 480);
  EXPECT_EQ(cam.rate_hz, 20.0);
  EXPECT_EQ(cam.intrinsics, Eigen::Vector4d(458.654, 457.296, 367.215, 248.375));
  EXPECT_EQ(cam.distortion_model, "radial-tangential");
  EXPECT_EQ(cam.distortion, Eigen::Vector4d(-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05));
  EXPECT_EQ(cam.T_b_c.matrix()(0, 1), -0.999880929698);
  EXPECT_EQ(cam.T_b_c.matrix()(2, 0), -0.0257744366974);
  EXPECT_EQ(cam.T_b_c.translation(),
            Eigen::Vector3d(-0.0216401454975, -0.064676986768, 0.00981073058949));
}

TEST(EurocIo, WrittenSensorYamlCarriesDirectiveAndOpenCvReadsIt) {
  const std::string dir = test::MakeTempDir("euroc_opencv");
  const CameraCalibration cam = MakeSyntheticDataset().cameras[0];
  WriteCameraYaml(cam, dir + "/sensor.yaml");
  EXPECT_EQ(ReadFile(dir + "/sensor.yaml").rfind("%YAML:1.0\n", 0), 0u);

  cv::FileStorage fs(dir + "/sensor.yaml", cv::FileStorage::READ);
  ASSERT_TRUE(fs.isOpened());
  EXPECT_EQ(static_cast<std::string>(fs["distortion_model"]), cam.distortion_model);
  std::vector<double> intrinsics, t_bs;
  fs["intrinsics"] >> intrinsics;
  fs["T_BS"]["data"] >> t_bs;
  ASSERT_EQ(intrinsics.size(), 4u);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(intrinsics[i], cam.intrinsics[i]);
  ASSERT_EQ(t_bs.size(), 16u);
  for (int i = 0; i < 16; ++i) EXPECT_EQ(t_bs[i], cam.T_b_c.matrix()(i / 4, i % 4));
  EXPECT_EQ(static_cast<int>(fs["T_BS"]["rows"]), 4);

  WriteCameraYaml(CameraCalibration(), dir + "/identity.yaml");  // T_BS of 0s and 1s
  cv::FileStorage identity_fs(dir + "/identity.yaml", cv::FileStorage::READ);
  ASSERT_TRUE(identity_fs.isOpened());
  EXPECT_TRUE(identity_fs["T_BS"]["data"][0].isReal());
  EXPECT_TRUE(identity_fs["rate_hz"].isReal());
  EXPECT_TRUE(identity_fs["resolution"][0].isInt());

  WriteImuYaml(MakeSyntheticDataset().imu_calibration, dir + "/imu.yaml");
  cv::FileStorage imu_fs(dir + "/imu.yaml", cv::FileStorage::READ);
  ASSERT_TRUE(imu_fs.isOpened());
  EXPECT_EQ(static_cast<double>(imu_fs["gyroscope_noise_density"]), 1.0 / 3.0 * 1e-4);
}

std::vector<ImuSample> ImuAt(const std::vector<Timestamp>& stamps) {
  std::vector<ImuSample> imu(stamps.size());
  for (std::size_t i = 0; i < stamps.size(); ++i) imu[i].t_ns = stamps[i];
  return imu;
}

TEST(EurocIo, FindImuGapsCountsIntervalsLongerThanThreePeriods) {
  const Timestamp p = kImuPeriodNs;
  EXPECT_EQ(FindImuGaps({}, 200.0).count, 0);
  const ImuGapReport none = FindImuGaps(ImuAt({0, p, 2 * p, 5 * p}), 200.0);  // exactly 3 periods
  EXPECT_EQ(none.count, 0);
  EXPECT_EQ(none.longest_ns, 0);
  const ImuGapReport gaps = FindImuGaps(ImuAt({0, p, 4 * p + 1, 5 * p, 15 * p, 16 * p}), 200.0);
  EXPECT_EQ(gaps.count, 2);
  EXPECT_EQ(gaps.longest_ns, 10 * p);
  EXPECT_EQ(FindImuGaps(ImuAt({0, 4 * p}), 100.0).count, 0);  // 2 periods at 100 Hz
}

TEST(EurocIo, ReadEurocReportsImuGapsWithoutFailing) {
  EurocDataset dataset = MakeSyntheticDataset();
  for (std::size_t i = 10; i < dataset.imu.size(); ++i) dataset.imu[i].t_ns += 20 * kImuPeriodNs;
  for (std::size_t i = 30; i < dataset.imu.size(); ++i) dataset.imu[i].t_ns += 4 * kImuPeriodNs;
  const std::string root = test::MakeTempDir("euroc_gaps");
  WriteEuroc(dataset, root);
  const EurocDataset read = ReadEuroc(root);
  EXPECT_EQ(read.imu.size(), dataset.imu.size());
  EXPECT_EQ(read.imu_gaps.count, 2);
  EXPECT_EQ(read.imu_gaps.longest_ns, dataset.imu[10].t_ns - dataset.imu[9].t_ns);
}

TEST(EurocIo, WritersRefuseWhatReadersWouldReject) {
  const std::string dir = test::MakeTempDir("euroc_refuse");
  std::vector<ImuSample> imu(1);
  imu[0].gyro_rad_s.x() = std::nan("");
  EXPECT_THROW(WriteImuCsv(imu, dir + "/imu.csv"), DatasetError);
  EXPECT_THROW(WriteFeaturesCsv({{0, 2, 1, {1.0, 2.0}}}, dir + "/f.csv"), DatasetError);
  EXPECT_THROW(WriteCameraCsv({{0, "a,b.png"}}, dir + "/cam.csv"), DatasetError);
  CameraCalibration cam;
  cam.distortion_model = "fisheye";
  EXPECT_THROW(WriteCameraYaml(cam, dir + "/cam.yaml"), DatasetError);
}

}  // namespace
}  // namespace vio::tools
