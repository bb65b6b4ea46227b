// Rigs that cannot be right, through the real binary: `vio simulate` writes the mistakes users make
// (the gyro in deg/s, the accelerometer in g, the cameras swapped; a camera-IMU clock offset of 2 s by
// shifting imu0/data.csv; the images exchanged), and `vio run` must stop with status bad_input and a problem that names
// the mistake and its fix, exit code 1, never crash, and write what it estimated (trajectory.txt,
// summary.json, timing.csv). The same flight written right runs ok.
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <sys/wait.h>

#include <gtest/gtest.h>

#include "test_data.h"

namespace vio {
namespace {

int Run(const std::string& command) {
  const int status = std::system((command + " > /dev/null 2>&1").c_str());
  EXPECT_TRUE(WIFEXITED(status)) << command;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// A 14 s synthetic flight (3 s at rest, `flags` to vio simulate: a moving start, a fault).
std::string Simulated(const std::string& name, const std::string& flags) {
  const std::string dir = test::MakeTempDir(name) + "/dataset";
  const std::string command = std::string(VIO_BINARY) + " simulate --output_dir=" + dir +
                              " --duration_s=14 --seed=3 " + flags;
  EXPECT_EQ(Run(command), 0) << command;
  return dir;
}

struct Outcome {
  int exit_code = -1;
  std::string summary;
  std::string out;
};

Outcome RunOn(const std::string& dataset, const std::string& name, const std::string& flags = "") {
  Outcome o;
  o.out = test::MakeTempDir(name);
  o.exit_code = Run(std::string(VIO_BINARY) + " run --dataset=" + dataset + " --output_dir=" + o.out + " " + flags);
  o.summary = ReadFile(o.out + "/summary.json");
  return o;
}

void ExpectBadInput(const Outcome& o, const std::string& message) {
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.summary.find("\"status\": \"bad_input\""), std::string::npos) << o.summary;
  EXPECT_NE(o.summary.find(message), std::string::npos) << "expected '" << message << "' in " << o.summary;
  for (const char* file : {"/trajectory.txt", "/timing.csv", "/config.yaml"}) {
    EXPECT_TRUE(test::PathExists(o.out + file)) << file;
  }
}

TEST(BadRig, TheFlightWrittenRightIsOk) {
  const Outcome o = RunOn(Simulated("rig_right", ""), "rig_right_run");
  EXPECT_EQ(o.exit_code, 0) << o.summary;
  EXPECT_NE(o.summary.find("\"status\": \"ok\""), std::string::npos);
}

TEST(BadRig, GyroInDegreesPerSecond) {
  const std::string dataset = Simulated("rig_gyro_deg", "--imu_gyro_units=deg_s");
  for (const std::string policy : {"swf", "msckf"}) {
    ExpectBadInput(RunOn(dataset, "rig_gyro_deg_" + policy, "--policy=" + policy),
                   "is imu0/data.csv's gyro in deg/s? It must be in rad/s");
  }
}

TEST(BadRig, GyroInDegreesPerSecondFromAMovingStart) {
  const std::string dataset = Simulated("rig_gyro_deg_moving", "--imu_gyro_units=deg_s --flight_start_s=8");
  ExpectBadInput(RunOn(dataset, "rig_gyro_deg_moving_run", "--policy=msckf"),
                 "is imu0/data.csv's gyro in deg/s? It must be in rad/s");
}

TEST(BadRig, AccelerometerInG) {
  const std::string dataset = Simulated("rig_accel_g", "--imu_accel_units=g");
  for (const std::string policy : {"swf", "msckf"}) {
    const Outcome o = RunOn(dataset, "rig_accel_g_" + policy, "--policy=" + policy);
    ExpectBadInput(o, "is imu0/data.csv's accelerometer in g? It must be in m/s^2");
    EXPECT_NE(o.summary.find("m/s^2 at rest, gravity is 9.81 m/s^2"), std::string::npos) << o.summary;
  }
}

TEST(BadRig, AccelerometerInGFromAMovingStart) {
  const std::string dataset = Simulated("rig_accel_g_moving", "--imu_accel_units=g --flight_start_s=8");
  ExpectBadInput(RunOn(dataset, "rig_accel_g_moving_run", "--policy=msckf"),
                 "is imu0/data.csv's accelerometer in g? It must be in m/s^2");
}

TEST(BadRig, SwappedCameras) {
  const std::string dataset = Simulated("rig_swapped", "--swap_cameras");
  ExpectBadInput(RunOn(dataset, "rig_swapped_run"), "with cam0 and cam1 exchanged (0 as given): are the cameras swapped?");
}

// The images exchanged (rendered with the true rig, written as cam1's and cam0's): the image front
// end's own check (stereo_swap_check.h).
TEST(BadRig, SwappedImages) {
  const std::string dir = test::MakeTempDir("rig_swapped_images") + "/dataset";
  ASSERT_EQ(vio::Run(std::string(VIO_BINARY) + " simulate --output_dir=" + dir +
                " --duration_s=4 --seed=2 --camera=images --swap_cameras"),
            0);
  ExpectBadInput(RunOn(dir, "rig_swapped_images_run"), "the stereo images match only with cam0 and cam1 exchanged");
}

// The IMU's clock 2 s ahead of the camera's: every IMU stamp moved 2 s earlier.
TEST(BadRig, CameraAndImuClocksTwoSecondsApart) {
  const std::string dataset = Simulated("rig_offset", "");
  const std::string imu_file = dataset + "/mav0/imu0/data.csv";
  std::istringstream in(ReadFile(imu_file));
  std::ofstream out(imu_file);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') {
      out << line << "\n";
      continue;
    }
    const std::size_t comma = line.find(',');
    out << std::stoll(line.substr(0, comma)) - 2'000'000'000LL << line.substr(comma) << "\n";
  }
  out.close();
  ExpectBadInput(RunOn(dataset, "rig_offset_run"), "are the camera and IMU clocks far apart");
}

}  // namespace
}  // namespace vio
