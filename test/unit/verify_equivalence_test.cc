// `vio verify` through the estimator: the equivalence theorems (4.3.1-4.3.5)
// and Algorithms 3 and 4 built in a vio::Window (linear factors, and stereo +
// IMU factors on SE3 states), the window's Gauss-Newton step and
// marginalization against the Kalman-form code, every mean moved by an
// innovation, negative controls on both sides, and the command with --json.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <fstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "vio/verify/verify.h"

namespace vio::tools {
namespace {

constexpr double kTolerance = 1e-8;

TEST(RunVerification, EveryTheoremRunsThroughTheWindowWithAnInnovationAndHolds) {
  for (const unsigned seed : {1u, 11u}) {
    VerifyOptions options;
    options.seed = seed;
    options.trials = 4;
    const VerifyReport report = RunVerification(options);
    EXPECT_TRUE(report.passed) << FormatVerifyReport(report);
    ASSERT_EQ(report.rows.size(), 2u * 7u + 2u * 5u);
    for (const VerifyRow& row : report.rows) {
      EXPECT_EQ(row.path, "window") << row.theorem << " " << row.kind;
      EXPECT_TRUE(row.passed) << row.theorem << " " << row.kind << " " << row.description;
      if (row.control) {
        EXPECT_GT(std::max(row.deviation.mean, row.deviation.covariance), 10 * kTolerance) << row.description;
        continue;
      }
      EXPECT_LE(row.deviation.mean, kTolerance) << row.theorem << " " << row.kind;
      EXPECT_LE(row.deviation.covariance, kTolerance) << row.theorem << " " << row.kind;
      EXPECT_GT(row.innovation, 1e-3) << row.theorem << " " << row.kind;
    }
  }
}

TEST(RunVerification, ControlsBreakBothSides) {
  VerifyOptions options;
  options.trials = 2;
  options.num_landmarks = 3;
  options.num_poses = 2;
  const VerifyReport report = RunVerification(options);
  std::vector<std::string> controls;
  for (const VerifyRow& row : report.rows) {
    if (row.control && row.kind == "nonlinear") controls.push_back(row.description);
  }
  const std::vector<std::string> expected = {
      "window: one factor's Jacobian off by 1e-4", "window: one Levenberg-Marquardt step instead of Gauss-Newton",
      "filter: EKF update with H off by 1e-5", "window: x_{t+1} marginalized instead of x_t",
      "filter: MSCKF update without null-space projection"};
  EXPECT_EQ(controls, expected);
  EXPECT_TRUE(report.passed) << FormatVerifyReport(report);
}

TEST(RunVerification, AToleranceBelowRoundOffFails) {
  VerifyOptions options;
  options.trials = 1;
  options.tolerance = 1e-300;  // nothing computed in floating point is that close
  const VerifyReport report = RunVerification(options);
  EXPECT_FALSE(report.passed);
  EXPECT_NE(FormatVerifyReport(report).find("FAIL"), std::string::npos);
  options.trials = 0;
  EXPECT_THROW(RunVerification(options), std::invalid_argument);
  options.trials = 1;
  options.num_poses = 1;
  EXPECT_THROW(RunVerification(options), std::invalid_argument);
}

/// Exit status and output of a shell command.
std::pair<int, std::string> RunShell(const std::string& command) {
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (pipe == nullptr) throw std::runtime_error("cannot run " + command);
  std::string output;
  char buffer[4096];
  while (fgets(buffer, sizeof(buffer), pipe) != nullptr) output += buffer;
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

std::pair<int, std::string> RunVio(const std::string& args) { return RunShell(std::string(VIO_BINARY) + " " + args); }

TEST(VerifyCommand, PrintsTheTableWritesJsonAndExitsZero) {
  const std::string json = testing::TempDir() + "/verify_rows.json";
  const auto [status, output] =
      RunVio("verify --trials=2 --seed=5 --num_landmarks=4 --num_poses=3 --json=" + json);
  EXPECT_EQ(status, 0) << output;
  for (const char* theorem : {"4.3.1", "4.3.2", "4.3.3", "4.3.4", "4.3.5", "Alg. 3", "Alg. 4"}) {
    EXPECT_NE(output.find(theorem), std::string::npos) << theorem << "\n" << output;
  }
  EXPECT_NE(output.find("seeds 5..6"), std::string::npos) << output;
  EXPECT_NE(output.find("PASS"), std::string::npos) << output;
  // The JSON parses, and says per row where it ran, the deviations and the innovation.
  const auto [parsed, summary] = RunShell(
      "python3 -c \"import json, sys; r = json.load(open('" + json +
      "')); rows = r['rows']; "
      "assert r['passed'] and len(rows) == 24; "
      "assert all(x['path'] == 'window' for x in rows); "
      "assert all(x['mean_deviation'] <= 1e-8 and x['covariance_deviation'] <= 1e-8 and x['innovation_norm'] > 0 "
      "for x in rows if not x['control']); "
      "assert all(max(x['mean_deviation'], x['covariance_deviation']) > 1e-8 for x in rows if x['control']); "
      "print(len(rows))\"");
  EXPECT_EQ(parsed, 0) << summary;
  EXPECT_EQ(summary, "24\n");
}

TEST(VerifyCommand, BadFlagsExitTwo) {
  EXPECT_EQ(RunVio("verify --num_poses=1").first, 2);
  EXPECT_EQ(RunVio("verify --trials=0").first, 2);
  EXPECT_EQ(RunVio("verify stray_argument").first, 2);
  const auto [status, output] = RunVio("verify --trials=1 --json=/nonexistent_folder/rows.json");
  EXPECT_EQ(status, 2);
  EXPECT_NE(output.find("--json"), std::string::npos) << output;
}

}  // namespace
}  // namespace vio::tools
