// MSCKF(10) against SWF(10) over the whole hybrid MH_04_difficult (real IMU
// and motion, simulated stereo features; the sequence whose 1.55 s of frames
// facing a wall are a tracking loss): the MSCKF within 1.5x of the SWF's ATE,
// the paper's "about as accurate as a window of the same size". With a fixed
// 5-sigma triangulation gate the MSCKF rejected every track for 2.8 s after
// the loss and ended at 3x.
#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/cli/run.h"
#include "vio/simulator/simulator.h"

namespace vio::tools {
namespace {

RunResult RunPolicy(const std::string& dataset, const std::string& policy) {
  RunRequest request;
  request.dataset_dir = dataset;
  request.output_dir = dataset + "_" + policy;
  request.show_progress = false;
  request.config.estimator.policy.policy = policy;
  request.config.estimator.policy.window_size = 10;
  return RunDataset(request);
}

TEST(MsckfHybridMh04, MsckfWithinOneAndAHalfTimesTheSwf) {
  VIO_REQUIRE_DATA(test::EurocSequence("MH_04_difficult"));
  SimulatorOptions sim;
  sim.from_euroc_dir = test::EurocSequence("MH_04_difficult");
  sim.output_dir = test::MakeTempDir("msckf_mh04") + "/MH_04_difficult";
  Simulate(sim);
  const RunResult swf = RunPolicy(sim.output_dir, "swf");
  const RunResult msckf = RunPolicy(sim.output_dir, "msckf");
  EXPECT_EQ(swf.status, "ok");
  EXPECT_EQ(msckf.status, "ok");
  EXPECT_GE(msckf.tracking.losses_beyond_window, 1);  // the stretch facing the wall
  ASSERT_TRUE(swf.evaluation && msckf.evaluation);
  EXPECT_LE(msckf.evaluation->ate.rmse_m, 1.5 * swf.evaluation->ate.rmse_m)
      << "MSCKF " << msckf.evaluation->ate.rmse_m << " m, SWF " << swf.evaluation->ate.rmse_m << " m";
  ::testing::Test::RecordProperty("msckf_ate_rmse_m", std::to_string(msckf.evaluation->ate.rmse_m));
  ::testing::Test::RecordProperty("swf_ate_rmse_m", std::to_string(swf.evaluation->ate.rmse_m));
}

}  // namespace
}  // namespace vio::tools
