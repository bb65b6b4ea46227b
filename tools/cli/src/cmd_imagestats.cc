// `vio imagestats`: real vs rendered image statistics, one table row per dataset.
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <gflags/gflags.h>

#include "commands.h"
#include "vio/cli/run_config.h"
#include "vio/simulator/image_statistics.h"

DECLARE_string(config);

DECLARE_string(datasets);  // cmd_sweep.cc: comma-separated ASL folders
DEFINE_int32(max_frames, 200, "stereo pairs read per dataset at most, from the first [count]");

namespace vio::tools {

int ImageStatsMain(const std::vector<std::string>& args) {
  if (!args.empty() || FLAGS_datasets.empty()) {
    std::cerr << "vio imagestats: --datasets is required and takes no positional argument (see `vio imagestats --help`)\n";
    return 2;
  }
  if (FLAGS_max_frames < 1) {
    std::cerr << "vio imagestats: --max_frames=" << FLAGS_max_frames << ": must be at least 1\n";
    return 2;
  }
  try {
    ImageStatisticsOptions options;
    options.max_frames = FLAGS_max_frames;
    options.frontend = LoadRunConfig(FLAGS_config).frontend;
    std::vector<ImageStatistics> rows;
    std::stringstream list(FLAGS_datasets);
    std::string dir;
    while (std::getline(list, dir, ',')) {
      if (!dir.empty()) rows.push_back(MeasureImageStatistics(dir, options));
    }
    std::cout << StatisticsTable(rows);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "vio imagestats: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace vio::tools
