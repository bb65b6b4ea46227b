// `vio run` on ROS 2 recordings of the real V1_01_easy_micro image pairs
// (skipped when the data is absent) writes the ASL folder's trajectory byte
// for byte: recordings `vio convert` wrote (MCAP with zstd chunks, a sqlite3
// bag folder) and one the independent writer wrote (tools/ros2_testdata:
// Foxglove's libraries, lz4 chunks; node needed, installed by
// `tools/install_deps.sh test`).
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "test_data.h"

namespace vio::tools {
namespace {

void Shell(const std::string& command, const std::string& log) {
  ASSERT_EQ(std::system((command + " > " + log + " 2>&1").c_str()), 0) << command << " (log: " << log << ")";
}

std::string FileText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Runs `vio run` on `dataset` into `out`; returns trajectory.txt.
std::string Trajectory(const std::string& dataset, const std::string& calibration, const std::string& out) {
  const std::string config = test::SourceDir() + "/config/euroc_stereo.yaml";
  Shell(std::string(VIO_BINARY) + " run --dataset=" + dataset + " --calibration=" + calibration +
            " --output_dir=" + out + " --config=" + config + " --minloglevel=1",
        out + ".log");
  EXPECT_NE(FileText(out + "/summary.json").find("\"status\": \"ok\""), std::string::npos) << out;
  return FileText(out + "/trajectory.txt");
}

TEST(Ros2Real, MicroClipRecordingsRunToTheAslTrajectory) {
  const std::string micro = test::EurocSequence("V1_01_easy_micro");
  VIO_REQUIRE_DATA(micro);
  const std::string dir = test::MakeTempDir("ros2_micro");
  const std::string asl = Trajectory(micro, micro, dir + "/run_asl");
  ASSERT_FALSE(asl.empty());
  const std::string vio(VIO_BINARY);
  Shell(vio + " convert --input=" + micro + " --output=" + dir + "/micro.mcap", dir + "/convert_mcap.log");
  EXPECT_EQ(Trajectory(dir + "/micro.mcap", micro, dir + "/run_mcap"), asl) << "MCAP, zstd chunks";
  Shell(vio + " convert --input=" + micro + " --output=" + dir + "/micro_db3 --storage=sqlite3",
        dir + "/convert_db3.log");
  EXPECT_EQ(Trajectory(dir + "/micro_db3", micro, dir + "/run_db3"), asl) << "sqlite3 bag folder";
  if (std::system("node --version > /dev/null 2>&1") != 0) {
    GTEST_SKIP() << "node is not installed (tools/install_deps.sh test): the independent writer's recording "
                    "was not run";
  }
  Shell("cd " + test::SourceDir() + "/tools/ros2_testdata && node write_bag.js --asl=" + micro + " --out=" + dir +
            "/foxglove.mcap --compression=lz4",
        dir + "/foxglove.log");
  EXPECT_EQ(Trajectory(dir + "/foxglove.mcap", micro, dir + "/run_foxglove"), asl) << "Foxglove's MCAP, lz4 chunks";
}

}  // namespace
}  // namespace vio::tools
