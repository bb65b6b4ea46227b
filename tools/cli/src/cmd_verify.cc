// `vio verify`: the design paper's equivalence theorems (4.3.1-4.3.5) and
// Algorithms 3 and 4 through vio::Window on random linear-Gaussian and
// nonlinear SE3 + stereo + IMU problems; exit code 1 when a theorem deviates
// beyond 1e-8 (or has no innovation, or did not run through the window) or a
// negative control is not detected. --json=FILE writes the rows as JSON.
#include <gflags/gflags.h>

#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.h"
#include "json_writer.h"
#include "vio/verify/verify.h"

// --seed is shared with `vio simulate` (defined in cmd_simulate.cc), --json
// with `vio eval` (cmd_eval.cc).
DECLARE_uint64(seed);
DECLARE_string(json);
DEFINE_int32(num_landmarks, 6, "vio verify: landmarks (EKF) / features (MSCKF) per random problem, 1..50");
DEFINE_int32(num_poses, 4, "vio verify: MSCKF poses per random problem, 2..20");
DEFINE_int32(trials, 20, "vio verify: random problems per kind (linear, nonlinear); trial k uses seed + k");

namespace vio::tools {
namespace {

VerifyOptions OptionsFromFlags(const std::vector<std::string>& args) {
  if (!args.empty()) throw std::invalid_argument("unexpected argument '" + args.front() + "'");
  if (FLAGS_num_landmarks < 1 || FLAGS_num_landmarks > 50) {
    throw std::invalid_argument("--num_landmarks must be in [1, 50]");
  }
  if (FLAGS_num_poses < 2 || FLAGS_num_poses > 20)
    throw std::invalid_argument("--num_poses must be in [2, 20]");
  if (FLAGS_trials < 1) throw std::invalid_argument("--trials must be >= 1");
  if (!FLAGS_json.empty() && !std::ofstream(FLAGS_json, std::ios::app)) {
    throw std::invalid_argument("--json: cannot open " + FLAGS_json + " for writing");
  }
  VerifyOptions options;
  options.seed = static_cast<unsigned>(FLAGS_seed);
  options.num_landmarks = FLAGS_num_landmarks;
  options.num_poses = FLAGS_num_poses;
  options.trials = FLAGS_trials;
  return options;
}

std::string RowJson(const VerifyRow& row) {
  std::ostringstream out;
  out << "{\"theorem\": " << JsonString(row.theorem) << ", \"description\": " << JsonString(row.description)
      << ", \"kind\": " << JsonString(row.kind) << ", \"control\": " << (row.control ? "true" : "false")
      << ", \"path\": " << JsonString(row.path) << ", \"mean_deviation\": " << JsonNumber(row.deviation.mean)
      << ", \"covariance_deviation\": " << JsonNumber(row.deviation.covariance)
      << ", \"innovation_norm\": " << JsonNumber(row.innovation) << ", \"passed\": " << (row.passed ? "true" : "false")
      << "}";
  return out.str();
}

std::string ReportJson(const VerifyReport& report) {
  const VerifyOptions& o = report.options;
  std::ostringstream out;
  out << "{\n  \"passed\": " << (report.passed ? "true" : "false") << ",\n  \"tolerance\": " << JsonNumber(o.tolerance)
      << ",\n  \"seed\": " << o.seed << ",\n  \"trials\": " << o.trials << ",\n  \"num_landmarks\": " << o.num_landmarks
      << ",\n  \"num_poses\": " << o.num_poses << ",\n  \"rows\": [";
  for (size_t i = 0; i < report.rows.size(); ++i) out << (i > 0 ? "," : "") << "\n    " << RowJson(report.rows[i]);
  out << "\n  ]\n}\n";
  return out.str();
}

}  // namespace

int VerifyMain(const std::vector<std::string>& args) {
  VerifyOptions options;
  try {
    options = OptionsFromFlags(args);
  } catch (const std::exception& e) {
    std::cerr << "vio verify: " << e.what() << "\n(see vio verify --help)\n";
    return 2;
  }
  const VerifyReport report = RunVerification(options);
  std::cout << FormatVerifyReport(report);
  if (!FLAGS_json.empty()) {
    std::ofstream out(FLAGS_json);
    out << ReportJson(report);
    if (!out.flush()) {
      std::cerr << "vio verify: --json: cannot write " << FLAGS_json << "\n";
      return 2;
    }
  }
  return report.passed ? 0 : 1;
}

}  // namespace vio::tools
