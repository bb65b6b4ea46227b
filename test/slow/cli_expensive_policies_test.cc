// The expensive policies over a short synthetic flight: EKF-SLAM and the
// iterated EKF (paper Algorithm 3: the previous state marginalized before the
// update, every landmark kept in a dense prior: the cost grows with the map,
// so the paper's variant flies a shorter flight) and the full batch (nothing
// marginalized, one final solve over everything, which must beat the online
// SWF).
#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/cli/run.h"
#include "vio/simulator/simulator.h"

namespace vio::tools {
namespace {

struct Case {
  std::string policy;
  std::string ekf_landmarks;
  double duration_s;
  double ate_bound_m;
};

class ExpensivePolicies : public ::testing::TestWithParam<Case> {};

std::string Dataset(double duration_s) {
  const std::string dir = test::MakeTempDir("ekf_synthetic") + "/dataset";
  SimulatorOptions options;
  options.output_dir = dir;
  options.duration_s = duration_s;
  options.seed = 5;
  Simulate(options);
  return dir;
}

TEST_P(ExpensivePolicies, TrackTheSyntheticFlight) {
  const Case& c = GetParam();
  RunRequest request;
  request.dataset_dir = Dataset(c.duration_s);
  request.output_dir = test::MakeTempDir("ekf_out_" + c.policy);
  request.show_progress = false;
  request.config.estimator.policy.policy = c.policy;
  request.config.estimator.policy.ekf_landmarks = c.ekf_landmarks;
  if (c.ekf_landmarks == "keep") request.config.estimator.policy.ekf_max_landmarks = 0;  // the paper's: the whole map
  const RunResult result = RunDataset(request);
  EXPECT_EQ(result.status, "ok");
  // Every frame after static initialization (IMU stillness over 1 s: 20 frames).
  EXPECT_EQ(result.frames_estimated + result.health.frames_waiting_init, result.frames);
  EXPECT_LE(result.health.frames_waiting_init, 21);
  ASSERT_TRUE(result.evaluation.has_value());
  EXPECT_LT(result.evaluation->ate.rmse_m, c.ate_bound_m);
}

INSTANTIATE_TEST_SUITE_P(Policies, ExpensivePolicies,
                         ::testing::Values(Case{"ekf", "keep", 4.5, 0.05}, Case{"iekf", "keep", 4.5, 0.05},
                                           Case{"ekf", "marginalize_unseen", 8.0, 0.05},
                                           Case{"batch", "keep", 8.0, 0.01}),
                         [](const auto& info) {
                           return info.param.policy + "_" + info.param.ekf_landmarks;
                         });

}  // namespace
}  // namespace vio::tools
