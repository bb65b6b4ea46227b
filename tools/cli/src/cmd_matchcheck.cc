// `vio matchcheck`: a run's observations (vio run --output_observations)
// against the world of the dataset `vio simulate` rendered (match_truth.h).
#include <filesystem>
#include <fstream>
#include <iostream>
#include <stdexcept>

#include <gflags/gflags.h>

#include "commands.h"
#include "vio/dataset/euroc_dataset.h"
#include "vio/dataset/observations_csv.h"
#include "vio/dataset/scene_csv.h"
#include "vio/frontend/stereo_rectifier.h"
#include "vio/simulator/match_truth.h"

DECLARE_string(dataset);
DECLARE_string(json);
DEFINE_string(run, "", "output folder of a `vio run --output_observations` on that dataset (its observations.csv)");
DEFINE_double(max_error_px, 3.0,
              "an observation is right when the point it sees is within this many pixel footprints of its "
              "landmark's point, or that point projects within this of its pixel, unhidden [px] valid: (0, inf)");

namespace vio::tools {
namespace {

// mav0/scene.csv of the dataset folder (the one holding mav0/, or mav0/ itself).
std::string ScenePath(const std::string& dataset_dir) {
  const std::filesystem::path root(dataset_dir);
  const std::filesystem::path inside = root / "mav0" / "scene.csv";
  if (std::filesystem::exists(inside)) return inside.string();
  if (std::filesystem::exists(root / "scene.csv")) return (root / "scene.csv").string();
  throw std::invalid_argument(dataset_dir + ": no mav0/scene.csv (only datasets made by `vio simulate` have one)");
}

MatchTruth Check(const std::string& dataset_dir, const std::string& run_dir, double max_error_px) {
  const SceneBoxes boxes = ReadSceneCsv(ScenePath(dataset_dir));
  EurocReadOptions read;
  read.read_imu = false;
  read.check_images = false;
  read.read_features = false;
  const EurocDataset dataset = ReadEuroc(dataset_dir, read);
  if (dataset.groundtruth.empty()) throw std::invalid_argument(dataset_dir + ": no ground truth");
  const std::string observations = run_dir + "/observations.csv";
  if (!std::filesystem::is_regular_file(observations)) {
    throw std::invalid_argument(observations + " not found (run `vio run --output_observations` first)");
  }
  Scene scene;
  scene.room = boxes.room;
  scene.boxes = boxes.boxes;
  const frontend::StereoRectifier rectifier(dataset.cameras[0], dataset.cameras[1]);
  MatchTruthOptions options;
  options.max_error_px = max_error_px;
  return CheckMatches(scene, rectifier.rectified(), dataset.groundtruth, ReadObservationsCsv(observations), options);
}

void PrintSummary(const MatchTruth& t, std::ostream& os) {
  os << t.observations << " observations in " << t.frames << " frames (" << t.unchecked << " unchecked), "
     << t.new_ids << " ids\n"
     << "continuing: " << t.continuing.correct << " correct, " << t.continuing.wrong << " wrong\n"
     << "reacquired (not in the previous frame): " << t.reacquired.correct << " correct, " << t.reacquired.wrong
     << " wrong (false rate " << t.FalseReacquisitionRate() << ")\n"
     << "missed returns (a point seen before, given a new id): " << t.missed_returns << " (reacquisition rate "
     << t.ReacquisitionRate() << ")\n";
}

}  // namespace

int MatchCheckMain(const std::vector<std::string>& args) {
  try {
    if (!args.empty()) throw std::invalid_argument("unexpected argument '" + args.front() + "'");
    if (FLAGS_dataset.empty() || FLAGS_run.empty()) throw std::invalid_argument("--dataset and --run are required");
    if (!(FLAGS_max_error_px > 0.0)) throw std::invalid_argument("--max_error_px must be > 0");
    const MatchTruth truth = Check(FLAGS_dataset, FLAGS_run, FLAGS_max_error_px);
    PrintSummary(truth, std::cout);
    const std::string json = FLAGS_json.empty() ? FLAGS_run + "/match_truth.json" : FLAGS_json;
    std::ofstream out(json);
    out << MatchTruthJson(truth) << "\n";
    if (!out) throw std::runtime_error(json + ": cannot write");
    std::cout << "written " << json << "\n";
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "vio matchcheck: " << e.what() << "\n";
    return 2;
  }
}

}  // namespace vio::tools
