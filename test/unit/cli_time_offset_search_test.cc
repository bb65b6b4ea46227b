// The time offset search at initialization through the real binary (docs/calibration.md): on a
// synthetic flight whose camera stamps are 60 ms early the run finds the offset beyond its prior
// (0 +- 5 ms), starts again with the prior there and ends as accurate as on the flight stamped right
// (the IMU weighed with its true noise, imu_noise_scale 1: with the default 10, suited to real IMUs,
// the synthetic flight's offset estimate is biased by a few ms, docs/calibration.md);
// 150 ms, beyond the search's range, stops the run with a problem that says what to set; on the flight
// stamped right the search changes nothing (byte-identical trajectory).
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include <sys/wait.h>

#include <gtest/gtest.h>

#include "test_data.h"

namespace vio {
namespace {

int Run(const std::string& command) {
  const int status = std::system((command + " > /dev/null 2>&1").c_str());
  EXPECT_TRUE(WIFEXITED(status)) << command;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The first number after "key": in a summary.json; NaN when absent.
double Number(const std::string& json, const std::string& key) {
  std::smatch match;
  if (!std::regex_search(json, match, std::regex("\"" + key + "\": (-?[0-9.eE+-]+)"))) return std::nan("");
  return std::stod(match[1]);
}

// The 15 s synthetic flight, its camera stamps `offset_ms` off the IMU's clock.
std::string Flight(double offset_ms) {
  const std::string dir = test::MakeTempDir("offset_search_flight") + "/dataset";
  const std::string command = std::string(VIO_BINARY) + " simulate --output_dir=" + dir +
                              " --duration_s=15 --seed=3 --time_offset_ms=" + std::to_string(offset_ms);
  EXPECT_EQ(Run(command), 0) << command;
  return dir;
}

struct Outcome {
  int exit_code = -1;
  std::string out, summary;
};

Outcome RunOn(const std::string& dataset, const std::string& flags = "") {
  Outcome o;
  o.out = test::MakeTempDir("offset_search_run");
  o.exit_code = Run(std::string(VIO_BINARY) + " run --dataset=" + dataset + " --output_dir=" + o.out + " " + flags);
  o.summary = ReadFile(o.out + "/summary.json");
  return o;
}

TEST(CliTimeOffsetSearch, AnOffsetBeyondThePriorStartsTheRunAgainWithThePriorThere) {
  const std::string flags = "--imu_noise_scale=1";
  const Outcome right = RunOn(Flight(0.0), flags);
  const std::string early = Flight(-60.0);
  const Outcome searched = RunOn(early, flags);
  const Outcome without = RunOn(early, flags + " --time_offset_search_ms=0");
  ASSERT_EQ(right.exit_code, 0) << right.summary;
  ASSERT_EQ(searched.exit_code, 0) << searched.summary;
  EXPECT_NE(searched.summary.find("\"restarted\": true"), std::string::npos) << searched.summary;
  EXPECT_NEAR(Number(searched.summary, "offset_ms"), -60.0, 25.0) << searched.summary;  // its sigma: ~11 ms
  EXPECT_NEAR(Number(searched.summary, "time_offset_ms"), -60.0, 1.0) << searched.summary;
  const double ate_right = Number(right.summary, "rmse_m"), ate = Number(searched.summary, "rmse_m");
  EXPECT_LE(ate, 1.05 * ate_right) << searched.summary;
  // Without the search the offset is estimated from 0 on, linearized 60 ms off at first (1.4x).
  EXPECT_GT(Number(without.summary, "rmse_m"), 1.2 * ate_right) << without.summary;
}

TEST(CliTimeOffsetSearch, AnOffsetBeyondItsRangeStopsTheRunSayingWhatToSet) {
  const Outcome o = RunOn(Flight(150.0));
  EXPECT_EQ(o.exit_code, 1);
  EXPECT_NE(o.summary.find("\"status\": \"bad_input\""), std::string::npos) << o.summary;
  EXPECT_NE(o.summary.find("time_offset_prior_mean_ms"), std::string::npos) << o.summary;
  EXPECT_NE(o.summary.find("time_offset_search_ms"), std::string::npos) << o.summary;
}

TEST(CliTimeOffsetSearch, OnARigStampedRightItChangesNothing) {
  const std::string flight = Flight(0.0);
  const Outcome searched = RunOn(flight), without = RunOn(flight, "--time_offset_search_ms=0");
  ASSERT_EQ(searched.exit_code, 0) << searched.summary;
  EXPECT_NE(searched.summary.find("\"restarted\": false"), std::string::npos) << searched.summary;
  const std::string a = ReadFile(searched.out + "/trajectory.txt");
  EXPECT_GT(a.size(), 1000u);
  EXPECT_EQ(a, ReadFile(without.out + "/trajectory.txt"));
}

}  // namespace
}  // namespace vio
