// `vio run --output_observations` then `vio matchcheck` (the real binary,
// VIO_BINARY) on a short synthetic dataset whose feature ids are the scene's
// landmarks: every id stands for one point, so nearly every observation is
// judged correct and no point comes back under a new id; bad inputs exit 2
// with a message naming what is missing.
#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/simulator/simulator.h"

namespace vio::tools {
namespace {

using ::testing::HasSubstr;

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Runs `vio <args>`; returns the exit code, the output in *output.
int Vio(const std::string& args, const std::string& log, std::string* output) {
  const int status = std::system((std::string(VIO_BINARY) + " " + args + " > " + log + " 2>&1").c_str());
  *output = ReadFile(log);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::int64_t JsonCount(const std::string& json, const std::string& pattern) {
  std::smatch m;
  if (!std::regex_search(json, m, std::regex(pattern))) return -1;
  return std::stoll(m[1].str());
}

TEST(MatchCheck, TrueIdsAreJudgedCorrectThroughTheCommandLine) {
  const std::string dir = test::MakeTempDir("matchcheck");
  SimulatorOptions sim;
  sim.output_dir = dir + "/dataset";
  sim.duration_s = 8.0;
  sim.seed = 5;
  Simulate(sim);
  ASSERT_TRUE(std::filesystem::exists(sim.output_dir + "/mav0/scene.csv"));
  std::string output;
  ASSERT_EQ(Vio("run --dataset=" + sim.output_dir + " --output_dir=" + dir + "/run --output_observations --policy=msckf",
                dir + "/run.log", &output),
            0)
      << output;
  ASSERT_EQ(Vio("matchcheck --dataset=" + sim.output_dir + " --run=" + dir + "/run", dir + "/check.log", &output), 0)
      << output;
  EXPECT_THAT(output, HasSubstr("continuing:"));
  const std::string json = ReadFile(dir + "/run/match_truth.json");
  const std::int64_t correct = JsonCount(json, "\"continuing\": \\{\"correct\": (\\d+)");
  const std::int64_t wrong = JsonCount(json, "\"continuing\": \\{\"correct\": \\d+, \"wrong\": (\\d+)");
  const std::int64_t observations = JsonCount(json, "\"observations\": (\\d+)");
  ASSERT_GT(correct, 1000) << json;
  EXPECT_LE(wrong, correct / 100) << json;
  EXPECT_EQ(JsonCount(json, "\"unchecked\": (\\d+)"), 0) << json;
  EXPECT_EQ(JsonCount(json, "\"missed_returns\": (\\d+)"), 0) << json;
  const std::string rows = ReadFile(dir + "/run/observations.csv");
  EXPECT_EQ(static_cast<std::int64_t>(std::count(rows.begin(), rows.end(), '\n')) - 1, observations);

  // Inputs that are not there: exit 2, the message says what is missing.
  EXPECT_EQ(Vio("matchcheck --dataset=" + sim.output_dir + " --run=" + dir, dir + "/a.log", &output), 2);
  EXPECT_THAT(output, HasSubstr("observations.csv not found (run `vio run --output_observations` first)"));
  std::filesystem::remove(sim.output_dir + "/mav0/scene.csv");
  EXPECT_EQ(Vio("matchcheck --dataset=" + sim.output_dir + " --run=" + dir + "/run", dir + "/b.log", &output), 2);
  EXPECT_THAT(output, HasSubstr("no mav0/scene.csv (only datasets made by `vio simulate` have one)"));
  EXPECT_EQ(Vio("matchcheck --run=" + dir + "/run", dir + "/c.log", &output), 2);
  EXPECT_THAT(output, HasSubstr("--dataset and --run are required"));
}

}  // namespace
}  // namespace vio::tools
