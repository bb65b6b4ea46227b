// A hybrid sequence cut in flight (`vio simulate --from_start_s`): the cut
// starts at the requested time with the IMU and ground truth cut there too,
// and `vio run` (init auto) starts it dynamically, at once, with status ok.
#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/cli/run.h"
#include "vio/simulator/simulator.h"

namespace vio::tools {
namespace {

TEST(HybridStart, V1_02CutThirtySecondsInStartsDynamically) {
  const std::string sequence = test::EurocSequence("V1_02_medium");
  VIO_REQUIRE_DATA(sequence);
  SimulatorOptions options;
  options.from_euroc_dir = sequence;
  options.from_start_s = 30.0;
  options.from_duration_s = 20.0;
  options.output_dir = test::MakeTempDir("hybrid_start") + "/dataset";
  const Simulation sim = BuildSimulation(options);
  WriteSimulation(sim, options, {});
  EurocReadOptions read;
  read.check_images = false;
  read.read_features = false;
  const Timestamp sequence_start_ns = ReadEuroc(sequence, read).frames[0].front().t_ns;  // the first cam0 row
  const Timestamp first_ns = sim.frames.front().t_ns;
  EXPECT_GE(first_ns, sequence_start_ns + SecondsToNanos(30.0));
  EXPECT_LT(first_ns, sequence_start_ns + SecondsToNanos(30.1));
  ASSERT_FALSE(sim.dataset.imu.empty());
  EXPECT_LE(sim.dataset.imu.front().t_ns, first_ns);  // the IMU covers the first frame
  EXPECT_GT(sim.dataset.imu.front().t_ns, first_ns - SecondsToNanos(0.01));  // and starts there
  EXPECT_GT(sim.dataset.groundtruth.front().t_ns, first_ns - SecondsToNanos(0.01));

  RunRequest request;
  request.dataset_dir = options.output_dir;
  request.output_dir = test::MakeTempDir("hybrid_start_run");
  request.show_progress = false;
  request.config.estimator.policy.policy = "msckf";
  request.config.estimator.policy.window_size = 10;
  const RunResult result = RunDataset(request);
  EXPECT_EQ(result.status, "ok");
  EXPECT_EQ(result.init.method, "dynamic");
  EXPECT_LE(result.init.wait_s, 0.5);
  EXPECT_GE(result.frames_estimated, 0.97 * result.frames);
  ASSERT_TRUE(result.evaluation);
  EXPECT_LT(result.evaluation->ate.rmse_m, 0.05);
}

}  // namespace
}  // namespace vio::tools
