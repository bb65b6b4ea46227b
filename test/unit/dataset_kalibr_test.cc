// Kalibr's camchain-imucam.yaml and imu.yaml (kalibr_calibration.h): a camchain written from EuRoC's
// own calibration reads back to it (T_BS = T_cam_imu^-1), the time shift becomes the camera's time
// offset, the IMU file is found beside the camchain, and each malformed file names file and line.
#include "vio/dataset/kalibr_calibration.h"

#include <fstream>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "euroc_calibration.h"
#include "kalibr_files.h"
#include "test_data.h"
#include "vio/dataset/euroc_dataset.h"

namespace vio::tools {
namespace {

// The camchain Kalibr writes for EuRoC's calibration (fixed layout: cam0's camera_model on line 8,
// distortion_model on 10, intrinsics on 11, timeshift on 14; cam1's T_cn_cnm1 from line 21).
std::string Camchain(double shift_s, const Eigen::Isometry3d& chain_error = Eigen::Isometry3d::Identity()) {
  return test::KalibrCamchain({test::EurocCamera(0), test::EurocCamera(1)}, shift_s, chain_error);
}

const std::string kImuYaml = test::KalibrImuYaml();
std::string Write(const std::string& dir, const std::string& name, const std::string& text) {
  const std::string path = dir + "/" + name;
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? text : text.replace(at, from.size(), to);
}

TEST(Kalibr, ACamchainOfEurocsCalibrationReadsBackToIt) {
  const std::string dir = test::MakeTempDir("kalibr_good");
  const std::string camchain = Write(dir, "camchain-imucam.yaml", Camchain(0.0123));
  const std::string imu = Write(dir, "imu.yaml", kImuYaml);
  EXPECT_TRUE(IsCalibrationFile(camchain));
  EXPECT_FALSE(IsCalibrationFile(dir));
  EXPECT_EQ(KalibrImuFileBeside(camchain), imu);
  const KalibrCalibration k = ReadKalibr(camchain, imu);
  for (int i = 0; i < 2; ++i) {
    const CameraCalibration euroc = test::EurocCamera(i);
    EXPECT_LE((k.cameras[i].T_b_c.matrix() - euroc.T_b_c.matrix()).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_EQ(k.cameras[i].intrinsics, euroc.intrinsics);
    EXPECT_EQ(k.cameras[i].distortion, euroc.distortion);
    EXPECT_EQ(k.cameras[i].distortion_model, "radial-tangential");
    EXPECT_EQ(k.cameras[i].width, 752);
    EXPECT_EQ(k.cameras[i].height, 480);
  }
  // Kalibr: t_imu = t_cam + shift; vio: an image stamped t was taken at IMU time t - camera_time_offset_ns.
  EXPECT_EQ(k.camera_time_offset_ns, -12'300'000);
  EXPECT_EQ(k.imu.rate_hz, 200.0);
  EXPECT_EQ(k.imu.gyro_noise_density, 1.6968e-04);
  EXPECT_EQ(k.imu.gyro_random_walk, 1.9393e-05);
  EXPECT_EQ(k.imu.accel_noise_density, 2.0e-3);
  EXPECT_EQ(k.imu.accel_random_walk, 3.0e-3);
}

TEST(Kalibr, ResultsFilesPairByNameAndNestTheImuUnderImu0) {
  const std::string dir = test::MakeTempDir("kalibr_results");
  const std::string camchain = Write(dir, "camchain-imucam-flight.yaml", Camchain(0.0));
  std::string nested = "imu0:\n";
  std::istringstream lines(kImuYaml);
  for (std::string line; std::getline(lines, line);) nested += "  " + line + "\n";
  const std::string imu = Write(dir, "imu-flight.yaml", nested);
  EXPECT_EQ(KalibrImuFileBeside(camchain), imu);
  EXPECT_EQ(ReadKalibr(camchain, imu).imu.gyro_noise_density, 1.6968e-04);
  const std::string lonely = Write(test::MakeTempDir("kalibr_lonely"), "camchain.yaml", Camchain(0.0));
  try {
    KalibrImuFileBeside(lonely);
    ADD_FAILURE() << "expected an error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("no IMU calibration beside it"), std::string::npos) << e.what();
  }
}

struct Malformed {
  std::string name;
  std::string camchain;
  std::string imu;
  std::string expected;  ///< "<file>:<line>: ..." after the folder
};

std::vector<Malformed> Cases() {
  const std::string good = Camchain(0.0);
  const Eigen::Isometry3d off = Eigen::Translation3d(0.01, 0, 0) * Eigen::Isometry3d::Identity();
  return {
      {"distortion", Replace(good, "distortion_model: radtan", "distortion_model: fov"), kImuYaml,
       "camchain-imucam.yaml:10: unknown distortion_model 'fov' (supported: radtan, equidistant)"},
      {"camera_model", Replace(good, "camera_model: pinhole", "camera_model: omni"), kImuYaml,
       "camchain-imucam.yaml:8: unknown camera_model 'omni' (supported: pinhole)"},
      {"intrinsics", Replace(good, "  intrinsics: [458.654, ", "  intrinsics: ["),
       kImuYaml, "camchain-imucam.yaml:11: 'intrinsics' must be a list of 4 numbers, got 3 values"},
      {"no_cam1", good.substr(0, good.find("cam1:")), kImuYaml, "camchain-imucam.yaml:1: missing key 'cam1'"},
      {"T_not_number", Replace(good, "  - [", "  - [abc, "), kImuYaml, "camchain-imucam.yaml:3: 'T_cam_imu' row 0"},
      {"chain", Camchain(0.0, off), kImuYaml, "camchain-imucam.yaml:22: 'T_cn_cnm1' disagrees with the cameras'"},
      {"shift_units", Replace(good, "timeshift_cam_imu: 0", "timeshift_cam_imu: 15000000"), kImuYaml,
       "camchain-imucam.yaml:14: 'timeshift_cam_imu' beyond 10 s: is it in seconds?"},
      {"imu_key", good, Replace(kImuYaml, "gyroscope_random_walk", "gyroscope_randomwalk"),
       "imu.yaml:2: missing key 'gyroscope_random_walk'"},
      {"imu_number", good, Replace(kImuYaml, "update_rate: 200", "update_rate: fast"),
       "imu.yaml:8: 'update_rate' is not a number: \"fast\""},
  };
}

TEST(Kalibr, MalformedFilesNameFileAndLine) {
  for (const Malformed& c : Cases()) {
    const std::string dir = test::MakeTempDir("kalibr_" + c.name);
    const std::string camchain = Write(dir, "camchain-imucam.yaml", c.camchain);
    const std::string imu = Write(dir, "imu.yaml", c.imu);
    try {
      ReadKalibr(camchain, imu);
      ADD_FAILURE() << c.name << ": expected an error";
    } catch (const DatasetError& e) {
      EXPECT_NE(std::string(e.what()).find(dir + "/" + c.expected), std::string::npos)
          << c.name << ": " << e.what();
    }
  }
}

}  // namespace
}  // namespace vio::tools
