// Finding and reading the ground truth an evaluation compares against.
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "vio/dataset/euroc_dataset.h"
#include "vio/evaluation/trajectory_eval.h"

namespace vio::tools {
namespace {

namespace fs = std::filesystem;

// The ground-truth file inside a sequence, mav0 or state_groundtruth_estimate0
// folder: ASL data.csv first, then TUM groundtruth_tum.txt.
fs::path FindGroundTruthFile(const fs::path& dir) {
  const fs::path folders[] = {dir / "mav0" / "state_groundtruth_estimate0",
                              dir / "state_groundtruth_estimate0", dir};
  std::string looked_for;
  for (const char* name : {"data.csv", "groundtruth_tum.txt"}) {
    for (const fs::path& folder : folders) {
      const fs::path candidate = folder / name;
      if (fs::is_regular_file(candidate)) return candidate;
      looked_for += "\n  " + candidate.string();
    }
  }
  throw std::invalid_argument("no ground truth in folder " + dir.string() + "; looked for:" +
                              looked_for);
}

}  // namespace

std::vector<GroundTruthState> ReadGroundTruthPath(const std::string& file_or_dir) {
  const fs::path path(file_or_dir);
  if (!fs::exists(path)) {
    throw std::invalid_argument("ground truth not found: " + file_or_dir);
  }
  const fs::path file = fs::is_directory(path) ? FindGroundTruthFile(path) : path;
  if (file.extension() == ".csv") return ReadGroundTruthCsv(file.string());
  return ReadTumTrajectory(file.string());
}

}  // namespace vio::tools
