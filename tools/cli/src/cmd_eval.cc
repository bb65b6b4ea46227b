// `vio eval`: trajectory error (ATE, RPE) of an estimate against ground truth,
// and with --covariance its consistency (NEES).
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gflags/gflags.h>

#include "commands.h"
#include "vio/evaluation/nees.h"
#include "vio/evaluation/trajectory_eval.h"

DEFINE_string(estimate, "", "estimated trajectory, TUM text: t[s] x y z qx qy qz qw per line");
DEFINE_string(groundtruth, "",
              "ground truth: EuRoC sequence folder, an ASL data.csv (17 columns) or a TUM text file");
DEFINE_string(alignment, "posyaw", "estimate-to-ground-truth alignment: posyaw|se3|sim3|none");
DEFINE_string(rpe_lengths, "1,2,5,10",
              "RPE sub-trajectory lengths along the ground truth [m], comma separated");
DEFINE_string(json, "",
              "also write the report as JSON to this file (optional; vio verify: its rows; vio matchcheck: "
              "default RUN_DIR/match_truth.json)");
DEFINE_string(covariance, "",
              "covariance.csv of the run (vio run --output_covariance): adds the NEES of position, orientation and "
              "pose, the estimate aligned at its first pose along the directions --alignment frees (optional)");
DEFINE_string(nees_csv, "", "with --covariance: per-frame NEES file; empty = nees.csv next to the covariance file");
DEFINE_double(max_gt_gap_s, 0,
              "ground truth is not interpolated across gaps longer than this; estimates inside are skipped; "
              "0 = 10 median ground-truth sample intervals (EuRoC: 0.05 s) [s] valid: [0, inf)");

namespace vio::tools {
namespace {

struct EvalRequest {
  std::string estimate_path;
  std::string groundtruth_path;
  std::string json_path;  ///< empty: no JSON
  std::string covariance_path;  ///< empty: no NEES
  std::string nees_path;        ///< per-frame NEES (with covariance_path)
  EvaluationOptions options;
};

std::vector<double> ParseLengths(const std::string& text) {
  std::vector<double> lengths_m;
  std::stringstream ss(text);
  std::string token;
  while (std::getline(ss, token, ',')) {
    size_t used = 0;
    double value = 0.0;
    try {
      value = std::stod(token, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != token.size() || !(value > 0.0)) {
      throw std::invalid_argument("--rpe_lengths: '" + token + "' is not a length > 0 [m]");
    }
    lengths_m.push_back(value);
  }
  return lengths_m;
}

EvalRequest EvalRequestFromFlags(const std::vector<std::string>& args) {
  if (!args.empty()) throw std::invalid_argument("unexpected argument '" + args.front() + "'");
  if (FLAGS_estimate.empty()) throw std::invalid_argument("--estimate=FILE is required");
  if (FLAGS_groundtruth.empty()) throw std::invalid_argument("--groundtruth=FILE_OR_DIR is required");
  if (!std::filesystem::is_regular_file(FLAGS_estimate)) {
    throw std::invalid_argument("estimate file not found: " + FLAGS_estimate);
  }
  EvalRequest request;
  request.estimate_path = FLAGS_estimate;
  request.groundtruth_path = FLAGS_groundtruth;
  request.json_path = FLAGS_json;
  request.covariance_path = FLAGS_covariance;
  if (!FLAGS_covariance.empty()) {
    if (!std::filesystem::is_regular_file(FLAGS_covariance)) {
      throw std::invalid_argument("--covariance: file not found: " + FLAGS_covariance);
    }
    request.nees_path = FLAGS_nees_csv.empty()
                            ? (std::filesystem::path(FLAGS_covariance).parent_path() / "nees.csv").string()
                            : FLAGS_nees_csv;
  }
  request.options.alignment = ParseAlignment(FLAGS_alignment);
  request.options.rpe_lengths_m = ParseLengths(FLAGS_rpe_lengths);
  if (!(FLAGS_max_gt_gap_s >= 0.0) || !std::isfinite(FLAGS_max_gt_gap_s)) {
    throw std::invalid_argument("--max_gt_gap_s: " + std::to_string(FLAGS_max_gt_gap_s) + " is not >= 0 [s]");
  }
  request.options.association.max_gap_ns = static_cast<Timestamp>(FLAGS_max_gt_gap_s * 1e9);
  return request;
}

void WriteJson(const TrajectoryEvaluation& evaluation, const std::optional<NeesResult>& nees,
               const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  std::string json = ToJson(evaluation);
  if (nees) json.insert(json.rfind("\n}"), ",\n  \"nees\": " + NeesJson(*nees));
  out << json << "\n";
  if (!out) throw std::runtime_error("error writing " + path);
}

void RunEval(const EvalRequest& request) {
  const std::vector<GroundTruthState> estimate = ReadTumTrajectory(request.estimate_path);
  const std::vector<GroundTruthState> groundtruth = ReadGroundTruthPath(request.groundtruth_path);
  const TrajectoryEvaluation evaluation = EvaluateTrajectory(estimate, groundtruth, request.options);
  std::cout << "estimate    " << request.estimate_path << " (" << estimate.size() << " poses)\n"
            << "groundtruth " << request.groundtruth_path << " (" << groundtruth.size()
            << " samples)\n"
            << ToText(evaluation);
  std::optional<NeesResult> nees;
  if (!request.covariance_path.empty()) {
    nees = EvaluateNees(estimate, groundtruth, ReadCovarianceCsv(request.covariance_path), request.options);
    std::cout << "NEES        " << nees->samples.size() << " frames with a covariance: position "
              << nees->mean_position << " (3 dof), orientation " << nees->mean_orientation << " (3 dof), pose "
              << nees->mean_pose << " (6 dof)\n";
    WriteNeesCsv(*nees, request.nees_path);
    std::cout << "nees        " << request.nees_path << "\n";
  }
  if (!request.json_path.empty()) {
    WriteJson(evaluation, nees, request.json_path);
    std::cout << "json        " << request.json_path << "\n";
  }
}

}  // namespace

int EvalMain(const std::vector<std::string>& args) {
  EvalRequest request;
  try {
    request = EvalRequestFromFlags(args);
  } catch (const std::exception& e) {
    std::cerr << "vio eval: " << e.what() << "\n(see vio eval --help)\n";
    return 2;
  }
  try {
    RunEval(request);
  } catch (const std::exception& e) {
    std::cerr << "vio eval: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace vio::tools
