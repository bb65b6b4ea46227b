// `vio verify`: the design paper's equivalence theorems (4.3.1-4.3.5, Remark
// 4.3.2) on random linear-Gaussian and nonlinear SE3 problems; exit code 1
// when a theorem deviates beyond 1e-8 or a negative control does not.
#include <gflags/gflags.h>

#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

#include "commands.h"
#include "vio/verify/verify.h"

// --seed is shared with `vio simulate` (defined in cmd_simulate.cc).
DECLARE_uint64(seed);
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
  VerifyOptions options;
  options.seed = static_cast<unsigned>(FLAGS_seed);
  options.num_landmarks = FLAGS_num_landmarks;
  options.num_poses = FLAGS_num_poses;
  options.trials = FLAGS_trials;
  return options;
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
  return report.passed ? 0 : 1;
}

}  // namespace vio::tools
