// SWF(10) over whole hybrid EuRoC sequences: the real IMU, the real motion,
// simulated stereo features (0.5 px) along it, static initialization.
// Bounds: the 0.03 m on V2_01_easy, and on V1_02_medium and
// MH_04_difficult the ATE a state-of-the-art open MSCKF reaches on this kind
// of input (0.026 m, 0.078 m).
#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/cli/run.h"
#include "vio/simulator/simulator.h"

namespace vio::tools {
namespace {

RunResult RunHybrid(const std::string& sequence) {
  SimulatorOptions sim;
  sim.from_euroc_dir = test::EurocSequence(sequence);
  sim.output_dir = test::MakeTempDir("swf_hybrid") + "/" + sequence;
  Simulate(sim);
  RunRequest request;
  request.dataset_dir = sim.output_dir;
  request.output_dir = sim.output_dir + "/run";
  request.show_progress = false;
  request.config.estimator.policy.window_size = 10;
  return RunDataset(request);
}

void ExpectAteBelow(const std::string& sequence, double bound_m) {
  const RunResult result = RunHybrid(sequence);
  EXPECT_EQ(result.status, "ok");
  // Every frame after static initialization (IMU stillness over 1 s, 20 frames at most) and
  // inside the IMU's span.
  EXPECT_EQ(result.frames_estimated + result.health.frames_waiting_init + result.health.frames_before_imu +
                result.health.frames_after_imu,
            result.frames);
  EXPECT_LE(result.health.frames_waiting_init, 20);
  ASSERT_TRUE(result.evaluation.has_value());
  EXPECT_LE(result.evaluation->ate.rmse_m, bound_m) << sequence;
  ::testing::Test::RecordProperty("ate_rmse_m", std::to_string(result.evaluation->ate.rmse_m));
}

TEST(SwfHybrid, V2_01_Easy) {
  VIO_REQUIRE_DATA(test::EurocSequence("V2_01_easy"));
  ExpectAteBelow("V2_01_easy", 0.03);
}

TEST(SwfHybrid, V1_02_Medium) {
  VIO_REQUIRE_DATA(test::EurocSequence("V1_02_medium"));
  ExpectAteBelow("V1_02_medium", 0.026);
}

TEST(SwfHybrid, MH_04_Difficult) {
  VIO_REQUIRE_DATA(test::EurocSequence("MH_04_difficult"));
  ExpectAteBelow("MH_04_difficult", 0.078);
}

}  // namespace
}  // namespace vio::tools
