// `vio convert`: an ASL folder to a ROS 1 bag or a ROS 2 recording, or either
// of those to an ASL folder.
#include <filesystem>
#include <iostream>

#include <gflags/gflags.h>

#include "commands.h"
#include "vio/dataset/euroc_dataset.h"
#include "vio/dataset/ros2_dataset.h"
#include "vio/dataset/rosbag_dataset.h"
#include "vio/cli/run_config.h"

DEFINE_string(input, "",
              "an ASL folder (holding mav0/, with images), a ROS 1 bag (FILE.bag) or a ROS 2 recording "
              "(FILE.mcap, FILE.db3 or a bag folder with metadata.yaml)");
DEFINE_string(output, "",
              "for an ASL input: FILE.bag (ROS 1), FILE.mcap, FILE.db3, or else a ROS 2 bag folder "
              "(--storage); for a bag input: an ASL folder");
DEFINE_string(storage, "mcap", "ROS 2 bag folder output: mcap or sqlite3 (.db3); FILE.mcap and FILE.db3 say it "
              "themselves");
DEFINE_string(compression, "zstd", "MCAP output: chunk compression, zstd, lz4 or none");

namespace vio::tools {
namespace {

void PrintCounts(const EurocDataset& dataset) {
  std::cout << FLAGS_input << " -> " << FLAGS_output << ": " << dataset.frames[0].size() << " stereo frames, "
            << dataset.imu.size() << " IMU samples, " << dataset.groundtruth.size() << " ground-truth poses\n";
}

int BagToAsl(const RunConfig& config, bool ros2) {
  if (config.calibration.calibration.empty()) {
    std::cerr << "vio convert: a recording carries no calibration: give --calibration=DIR (mav0/*/sensor.yaml)\n";
    return 2;
  }
  EurocDataset dataset = ros2 ? ReadRos2Bag(FLAGS_input, config.bag) : ReadBag(FLAGS_input, config.bag);
  ApplyCalibrationFrom(config.calibration.calibration, &dataset);
  WriteAslFromBag(dataset, FLAGS_output);
  PrintCounts(dataset);
  return 0;
}

}  // namespace

int ConvertMain(const std::vector<std::string>& args) {
  if (!args.empty() || FLAGS_input.empty() || FLAGS_output.empty()) {
    std::cerr << "vio convert: --input and --output are required (see `vio convert --help`)\n";
    return 2;
  }
  if (FLAGS_storage != "mcap" && FLAGS_storage != "sqlite3") {
    std::cerr << "vio convert: --storage=" << FLAGS_storage << ": mcap or sqlite3\n";
    return 2;
  }
  if (FLAGS_compression != "zstd" && FLAGS_compression != "lz4" && FLAGS_compression != "none") {
    std::cerr << "vio convert: --compression=" << FLAGS_compression << ": zstd, lz4 or none\n";
    return 2;
  }
  const RunConfig config = LoadRunConfig("");
  const bool ros2 = IsRos2BagPath(FLAGS_input);
  if (ros2 || IsBagPath(FLAGS_input)) return BagToAsl(config, ros2);
  const EurocDataset dataset = ReadEuroc(FLAGS_input);
  if (!dataset.has_images) {
    std::cerr << "vio convert: " << FLAGS_input << " has no images (mav0/cam0/data/) to write into a bag\n";
    return 1;
  }
  if (std::filesystem::path(FLAGS_output).extension() == ".bag") {
    WriteBag(dataset, FLAGS_output, config.bag);
  } else {
    WriteRos2Bag(dataset, FLAGS_output, config.bag, Ros2WriteOptions{FLAGS_storage, FLAGS_compression});
  }
  PrintCounts(dataset);
  return 0;
}

}  // namespace vio::tools
