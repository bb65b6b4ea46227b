// The expensive policies over a short synthetic flight: EKF-SLAM and the
// iterated EKF (SWF(1) keeping every visible landmark: a dense prior over
// them, which is what an EKF is) and the full batch (nothing marginalized,
// one final solve over everything, which must beat the online SWF).
#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/cli/run.h"
#include "vio/simulator/simulator.h"

namespace vio::tools {
namespace {

class ExpensivePolicies : public ::testing::TestWithParam<std::string> {};

TEST_P(ExpensivePolicies, TrackTheSyntheticFlight) {
  static const std::string dataset = [] {
    SimulatorOptions options;
    options.output_dir = test::MakeTempDir("ekf_synthetic") + "/dataset";
    options.duration_s = 8.0;
    options.seed = 5;
    Simulate(options);
    return options.output_dir;
  }();
  RunRequest request;
  request.dataset_dir = dataset;
  request.output_dir = test::MakeTempDir("ekf_out_" + GetParam());
  request.show_progress = false;
  request.config.estimator.policy.policy = GetParam();
  const RunResult result = RunDataset(request);
  EXPECT_EQ(result.status, "ok");
  // Every frame after static initialization (IMU stillness over 1 s: 20 frames).
  EXPECT_EQ(result.frames_estimated + result.health.frames_waiting_init, result.frames);
  EXPECT_LE(result.health.frames_waiting_init, 21);
  ASSERT_TRUE(result.evaluation.has_value());
  EXPECT_LT(result.evaluation->ate.rmse_m, GetParam() == std::string("batch") ? 0.01 : 0.05);
}

INSTANTIATE_TEST_SUITE_P(Policies, ExpensivePolicies, ::testing::Values("ekf", "iekf", "batch"));

}  // namespace
}  // namespace vio::tools
