// `vio convert`: an ASL folder to a ROS 1 bag, or a bag to an ASL folder.
#include <filesystem>
#include <iostream>

#include <gflags/gflags.h>

#include "commands.h"
#include "vio/dataset/euroc_dataset.h"
#include "vio/dataset/rosbag_dataset.h"
#include "vio/cli/run_config.h"

DEFINE_string(input, "", "an ASL folder (holding mav0/, with images) or a ROS 1 bag (FILE.bag)");
DEFINE_string(output, "", "a bag (FILE.bag) for an ASL input, an ASL folder for a bag input");

namespace vio::tools {

int ConvertMain(const std::vector<std::string>& args) {
  if (!args.empty() || FLAGS_input.empty() || FLAGS_output.empty()) {
    std::cerr << "vio convert: --input and --output are required (see `vio convert --help`)\n";
    return 2;
  }
  const RunConfig config = LoadRunConfig("");
  if (IsBagPath(FLAGS_input)) {
    if (config.calibration.calibration.empty()) {
      std::cerr << "vio convert: a bag carries no calibration: give --calibration=DIR (mav0/*/sensor.yaml)\n";
      return 2;
    }
    EurocDataset dataset = ReadBag(FLAGS_input, config.bag);
    ApplyCalibrationFrom(config.calibration.calibration, &dataset);
    WriteAslFromBag(dataset, FLAGS_output);
    std::cout << FLAGS_input << " -> " << FLAGS_output << ": " << dataset.frames[0].size() << " stereo frames, "
              << dataset.imu.size() << " IMU samples, " << dataset.groundtruth.size() << " ground-truth poses\n";
    return 0;
  }
  if (std::filesystem::path(FLAGS_output).extension() != ".bag") {
    std::cerr << "vio convert: --output=" << FLAGS_output << ": an ASL input converts to a bag (FILE.bag)\n";
    return 2;
  }
  const EurocDataset dataset = ReadEuroc(FLAGS_input);
  if (!dataset.has_images) {
    std::cerr << "vio convert: " << FLAGS_input << " has no images (mav0/cam0/data/) to write into a bag\n";
    return 1;
  }
  WriteBag(dataset, FLAGS_output, config.bag);
  std::cout << FLAGS_input << " -> " << FLAGS_output << ": " << dataset.frames[0].size() << " stereo frames, "
            << dataset.imu.size() << " IMU samples, " << dataset.groundtruth.size() << " ground-truth poses\n";
  return 0;
}

}  // namespace vio::tools
