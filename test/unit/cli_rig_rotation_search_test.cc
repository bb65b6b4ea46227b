// The rig rotation search at initialization end to end (docs/calibration.md): a synthetic flight
// whose sensor.yaml has both cameras turned by 5 deg in the body (simulated with the true rig) is
// found by the search, run again with the cameras turned and the extrinsics estimated online, and
// ends with the rig within 0.2 deg of the truth and the accuracy of the clean flight with the
// extrinsics estimated; on the clean flight the search finds no turn beyond the prior and the
// trajectory is byte-identical to one without it.
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/cli/run.h"
#include "vio/simulator/simulator.h"

namespace vio::tools {
namespace {

const Eigen::Vector3d kAxis = Eigen::Vector3d(1.0, -2.0, 0.5).normalized();

std::string SyntheticDataset(double error_deg) {
  SimulatorOptions options;
  options.output_dir = test::MakeTempDir("rig_search") + "/dataset";
  options.duration_s = 20.0;
  options.seed = 3;
  options.rig.extrinsic_error_deg = error_deg;
  options.rig.rotation_axis = kAxis;
  options.rig.translation_direction = Eigen::Vector3d::UnitX();
  Simulate(options);
  return options.output_dir;
}

RunResult RunWith(const std::string& dataset, bool search, std::string* output, bool extrinsics = false) {
  RunRequest request;
  request.dataset_dir = dataset;
  request.output_dir = test::MakeTempDir("rig_search_run");
  *output = request.output_dir;
  request.show_progress = false;
  request.config.estimator.policy.policy = "swf";
  request.config.estimator.model.extrinsics_rotation_search = search;
  request.config.estimator.model.estimate_extrinsics = extrinsics;
  // The search's own restart (with the extrinsics probe, cli_run_extrinsics_test, the probe decides
  // after the turn instead).
  request.config.estimator.model.extrinsics_probe_s = 0;
  // The simulator's IMU noise is the datasheet's: the matching model (cli_run_time_offset_test).
  request.config.estimator.model.imu_noise_scale = 1.0;
  return RunDataset(request);
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

TEST(RigRotationSearch, FindsAFiveDegreeTurnAndTheCleanFlightIsUnchanged) {
  const std::string clean = SyntheticDataset(0.0);
  std::string clean_out, clean_without_out;
  const RunResult reference = RunWith(clean, /*search=*/true, &clean_out);
  ASSERT_EQ(reference.status, "ok");
  ASSERT_TRUE(reference.calibration.rig_rotation_search_deg.has_value());
  EXPECT_FALSE(reference.calibration.rig_rotation_search_restarted);
  EXPECT_LT(reference.calibration.rig_rotation_search_deg->norm(), 2.0);
  EXPECT_FALSE(reference.calibration.extrinsics_estimated);
  const RunResult without = RunWith(clean, /*search=*/false, &clean_without_out);
  ASSERT_EQ(without.status, "ok");
  EXPECT_FALSE(without.calibration.rig_rotation_search_deg.has_value());
  const std::string trajectory = ReadFile(clean_out + "/trajectory.txt");
  EXPECT_FALSE(trajectory.empty());
  EXPECT_EQ(trajectory, ReadFile(clean_without_out + "/trajectory.txt"));

  const std::string turned = SyntheticDataset(5.0);
  std::string out, held_out;
  const RunResult run = RunWith(turned, /*search=*/true, &out);
  ASSERT_EQ(run.status, "ok");
  ASSERT_TRUE(run.calibration.rig_rotation_search_deg.has_value());
  EXPECT_TRUE(run.calibration.rig_rotation_search_restarted);
  EXPECT_TRUE(run.calibration.rig_rotation_search_excited);
  // Written = E * true: the rig is turned back by -5 deg about the axis. The search is within the
  // online correction's reach (measured 1.66 deg off here; 0.15 deg on hybrid V2_01); the correction
  // takes the rest.
  EXPECT_LT((*run.calibration.rig_rotation_search_deg + 5.0 * kAxis).norm(), 2.0)
      << run.calibration.rig_rotation_search_deg->transpose();
  EXPECT_TRUE(run.calibration.extrinsics_estimated);
  const Eigen::Vector3d error_deg = run.calibration.extrinsics_rotation_deg + 5.0 * kAxis;
  EXPECT_LT(error_deg.norm(), 0.2) << run.calibration.extrinsics_rotation_deg.transpose();
  ASSERT_TRUE(run.evaluation.has_value());
  ASSERT_TRUE(reference.evaluation.has_value());
  const RunResult held = RunWith(turned, /*search=*/false, &held_out);
  ASSERT_TRUE(held.evaluation.has_value());
  // The restarted run estimates the extrinsics: it ends where the clean flight does with them
  // estimated (that state's own cost on a clean rig, 1.5x here, is docs/calibration.md's).
  std::string estimated_out;
  const RunResult estimated = RunWith(clean, /*search=*/false, &estimated_out, /*extrinsics=*/true);
  ASSERT_TRUE(estimated.evaluation.has_value());
  EXPECT_LT(run.evaluation->ate.rmse_m, 1.1 * estimated.evaluation->ate.rmse_m);
  EXPECT_LT(estimated.evaluation->ate.rmse_m, 2.0 * reference.evaluation->ate.rmse_m);
  EXPECT_LT(run.evaluation->ate.rmse_m, 0.5 * held.evaluation->ate.rmse_m);
}

}  // namespace
}  // namespace vio::tools
