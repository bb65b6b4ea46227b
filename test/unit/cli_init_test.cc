// How `vio run` starts (init auto by default) and what its status says about
// it, on synthetic flights: a flight moving at t = 0 starts dynamically
// within a second and is ok; one whose first seconds give nothing to track
// starts late (status late_init, the seconds and frames lost in `problems`,
// exit code 1); forced static on a flight that never stops never starts
// (not_initialized); the default flight (3 s at rest) starts static at once.
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include <sys/wait.h>

#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/cli/run.h"
#include "vio/simulator/simulator.h"

namespace vio::tools {
namespace {

// A 12 s synthetic flight already at full pace at t = 0 (5 s static + ramp
// skipped), with an optional blackout (nothing to track) from the start.
std::string MovingFlight(const std::string& name, double blackout_s) {
  SimulatorOptions options;
  options.output_dir = test::MakeTempDir(name) + "/dataset";
  options.duration_s = 12.0;
  options.seed = 5;
  options.trajectory.start_offset_s = 8.0;
  if (blackout_s > 0) options.gaps.blackouts = {{0.0, blackout_s}};
  Simulate(options);
  return options.output_dir;
}

RunResult RunWithInit(const std::string& dataset, const std::string& output_dir, const std::string& init = "auto",
                      double max_gyro_std = 0.05) {
  RunRequest request;
  request.config.estimator.init.static_max_gyro_std = max_gyro_std;
  request.dataset_dir = dataset;
  request.output_dir = output_dir;
  request.show_progress = false;
  request.config.estimator.init.init = init;
  return RunDataset(request);
}

TEST(RunInit, FlightMovingAtStartStartsDynamicallyWithinASecond) {
  const std::string dataset = MovingFlight("init_moving", 0.0);
  const RunResult result = RunWithInit(dataset, test::MakeTempDir("init_moving_run"));
  EXPECT_EQ(result.status, "ok");
  EXPECT_EQ(result.init.method, "dynamic");
  EXPECT_LE(result.init.wait_s, 1.0);
  EXPECT_GE(result.frames_estimated, 0.97 * result.frames);
  ASSERT_TRUE(result.evaluation);
  EXPECT_LT(result.evaluation->ate.rmse_m, 0.1);
}

TEST(RunInit, ThreeSecondsWithNothingToTrackIsALateStart) {
  const std::string dataset = MovingFlight("init_late", 3.0);
  const std::string out = test::MakeTempDir("init_late_run");
  const RunResult result = RunWithInit(dataset, out);
  EXPECT_EQ(result.status, "late_init");
  EXPECT_EQ(result.init.method, "dynamic");
  EXPECT_GT(result.init.wait_s, 2.5);
  EXPECT_GE(result.health.frames_waiting_init, 50);  // 3 s at 20 Hz, less the dynamic window's frames
  ASSERT_FALSE(result.problems.empty());
  EXPECT_NE(result.problems.back().find("late initialization (dynamic): waited"), std::string::npos)
      << result.problems.back();
  EXPECT_NE(result.problems.back().find("3.20 s and 64 frames"), std::string::npos) << result.problems.back();
  EXPECT_NE(result.problems.back().find("last reason: static: the IMU is moving"), std::string::npos)
      << result.problems.back();
  EXPECT_GT(result.frames_estimated, 0);  // what was estimated is written
  std::ifstream summary(out + "/summary.json");
  std::stringstream text;
  text << summary.rdbuf();
  EXPECT_NE(text.str().find("\"status\": \"late_init\""), std::string::npos);
  EXPECT_NE(text.str().find("\"init\": {\"method\": \"dynamic\""), std::string::npos);

  // The command line says so with its exit code (1: not ok).
  const std::string command = std::string(VIO_BINARY) + " run --dataset=" + dataset + " --output_dir=" +
                              test::MakeTempDir("init_late_cli") + " > /dev/null 2>&1";
  const int status = std::system(command.c_str());
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 1);
}

TEST(RunInit, ForcedStaticOnAFlightThatNeverStopsNeverStarts) {
  const std::string dataset = MovingFlight("init_never", 0.0);
  // This flight's gyro std comes near the default 0.05 rad/s at times: a stricter bound keeps it moving.
  const RunResult result = RunWithInit(dataset, test::MakeTempDir("init_never_run"), "static", 0.02);
  EXPECT_EQ(result.status, "not_initialized");
  EXPECT_EQ(result.frames_estimated, 0);
  EXPECT_EQ(result.init.method, "");
  EXPECT_NE(result.init.last_reason.find("the IMU is moving"), std::string::npos) << result.init.last_reason;
}

TEST(RunInit, FlightStartingAtRestStartsStaticWithEveryFrameEstimated) {
  SimulatorOptions options;
  options.output_dir = test::MakeTempDir("init_rest") + "/dataset";
  options.duration_s = 8.0;
  options.seed = 5;
  Simulate(options);
  const RunResult result = RunWithInit(options.output_dir, test::MakeTempDir("init_rest_run"));
  EXPECT_EQ(result.status, "ok");
  EXPECT_EQ(result.init.method, "static");
  EXPECT_EQ(result.init.wait_s, 0.0);  // the frames of the still window get the initial pose
  EXPECT_EQ(result.frames_estimated, result.frames);
}

}  // namespace
}  // namespace vio::tools
