// `vio run --calibration=camchain-imucam.yaml` through the binary: Kalibr's files written from a
// dataset's own sensor.yaml give the run of the sensor.yaml (poses equal to 1e-9), and Kalibr's
// timeshift_cam_imu moves every frame onto the IMU's clock (t_imu = t_cam + shift).
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <sys/wait.h>

#include <gtest/gtest.h>

#include "kalibr_files.h"
#include "test_data.h"
#include "vio/dataset/euroc_dataset.h"
#include "vio/simulator/simulator.h"

namespace vio::tools {
namespace {

std::vector<std::vector<double>> ReadTrajectory(const std::string& path) {
  std::vector<std::vector<double>> rows;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::vector<double> row;
    for (double v; fields >> v;) row.push_back(v);
    rows.push_back(row);
  }
  return rows;
}

int RunVio(const std::string& arguments) {
  const int status = std::system((std::string(VIO_BINARY) + " run " + arguments + " > /dev/null 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

class KalibrRun : public ::testing::Test {
 protected:
  void SetUp() override {
    SimulatorOptions options;
    options.output_dir = test::MakeTempDir("kalibr_run") + "/dataset";
    options.duration_s = 8.0;
    options.seed = 4;
    Simulate(options);
    dataset_ = options.output_dir;
    EurocReadOptions calibration_only;
    calibration_only.read_groundtruth = calibration_only.read_features = false;
    calibration_only.check_images = false;
    calibration_ = ReadEuroc(dataset_, calibration_only);
  }

  // A Kalibr folder for the dataset's calibration with the given time shift; returns the camchain.
  std::string Camchain(double shift_s) const {
    const std::string dir = test::MakeTempDir("kalibr_files");
    std::ofstream(dir + "/camchain-imucam.yaml")
        << test::KalibrCamchain({calibration_.cameras[0], calibration_.cameras[1]}, shift_s);
    std::ofstream(dir + "/imu.yaml") << test::KalibrImuYaml(calibration_.imu_calibration);
    return dir + "/camchain-imucam.yaml";
  }

  std::string dataset_;
  EurocDataset calibration_;
};

TEST_F(KalibrRun, TheCamchainOfTheSensorYamlGivesTheSameRun) {
  const std::string own = test::MakeTempDir("kalibr_own"), kalibr = test::MakeTempDir("kalibr_cam");
  ASSERT_EQ(RunVio("--dataset=" + dataset_ + " --output_dir=" + own), 0);
  ASSERT_EQ(RunVio("--dataset=" + dataset_ + " --output_dir=" + kalibr + " --calibration=" + Camchain(0.0)), 0);
  const auto a = ReadTrajectory(own + "/trajectory.txt"), b = ReadTrajectory(kalibr + "/trajectory.txt");
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 100u);
  double largest = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (std::size_t j = 0; j < a[i].size(); ++j) largest = std::max(largest, std::abs(a[i][j] - b[i][j]));
  }
  EXPECT_LE(largest, 1e-9);
}

TEST_F(KalibrRun, TheTimeShiftMovesTheFramesOntoTheImuClock) {
  const std::string own = test::MakeTempDir("kalibr_noshift"), shifted = test::MakeTempDir("kalibr_shift");
  // The offset not estimated: the frames' stamps are the shifted ones exactly.
  const std::string flags = " --estimate_time_offset=false --dataset=" + dataset_;
  ASSERT_EQ(RunVio(flags + " --output_dir=" + own + " --calibration=" + Camchain(0.0)), 0);
  RunVio(flags + " --output_dir=" + shifted + " --calibration=" + Camchain(0.004));
  const auto a = ReadTrajectory(own + "/trajectory.txt"), b = ReadTrajectory(shifted + "/trajectory.txt");
  ASSERT_FALSE(a.empty());
  ASSERT_FALSE(b.empty());
  // The last frame, 4 ms later, is past the IMU's last sample: not estimated.
  ASSERT_EQ(b.size() + 1, a.size());
  for (std::size_t i = 0; i < b.size(); ++i) EXPECT_NEAR(b[i][0] - a[i][0], 0.004, 1e-6) << i;
  std::stringstream summary;
  summary << std::ifstream(shifted + "/summary.json").rdbuf();
  EXPECT_NE(summary.str().find("\"time_offset_calibration_ms\": -4"), std::string::npos) << summary.str();
}

TEST_F(KalibrRun, ACamchainWithoutItsImuFileIsAnError) {
  const std::string dir = test::MakeTempDir("kalibr_noimu");
  std::ofstream(dir + "/camchain-imucam.yaml")
      << test::KalibrCamchain({calibration_.cameras[0], calibration_.cameras[1]}, 0.0);
  EXPECT_EQ(RunVio("--dataset=" + dataset_ + " --output_dir=" + test::MakeTempDir("kalibr_noimu_run") +
                " --calibration=" + dir + "/camchain-imucam.yaml"),
            1);
}

}  // namespace
}  // namespace vio::tools
