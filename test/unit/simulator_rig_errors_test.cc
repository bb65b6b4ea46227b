// `vio simulate`'s rig errors (rig_errors.h): the written stamps and T_BS are the true ones moved by
// exactly the asked offset and rigid error, IMU and ground truth untouched, the stereo baseline kept.
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "test_data.h"
#include "vio/dataset/euroc_dataset.h"
#include "vio/simulator/rig_errors.h"
#include "vio/simulator/simulator.h"

namespace vio::tools {
namespace {

SimulatorOptions Options(const std::string& dir) {
  SimulatorOptions options;
  options.output_dir = dir;
  options.seed = 3;
  options.duration_s = 4.0;
  return options;
}

double AngleDeg(const Eigen::Matrix3d& R) { return Eigen::AngleAxisd(R).angle() * 180.0 / M_PI; }

TEST(SimulatorRigErrorsTest, WritesShiftedStampsAndMovedRig) {
  const std::string base = test::MakeTempDir("vio_sim_rig");
  Simulate(Options(base + "/clean"));
  SimulatorOptions options = Options(base + "/rig");
  options.rig.time_offset_ms = 15.0;
  options.rig.extrinsic_error_deg = 1.0;
  options.rig.extrinsic_error_m = 0.015;
  Simulate(options);
  const EurocDataset clean = ReadEuroc(base + "/clean");
  const EurocDataset rig = ReadEuroc(base + "/rig");

  ASSERT_EQ(clean.frames[0].size(), rig.frames[0].size());
  ASSERT_FALSE(clean.frames[0].empty());
  for (int k = 0; k < 2; ++k) {
    for (size_t i = 0; i < clean.frames[k].size(); ++i) {
      EXPECT_EQ(rig.frames[k][i].t_ns - clean.frames[k][i].t_ns, 15'000'000);
    }
  }
  ASSERT_EQ(clean.features.size(), rig.features.size());
  for (size_t i = 0; i < clean.features.size(); ++i) {
    EXPECT_EQ(rig.features[i].t_ns - clean.features[i].t_ns, 15'000'000);
    EXPECT_EQ(rig.features[i].uv_px, clean.features[i].uv_px);  // simulated with the true rig
  }
  ASSERT_EQ(clean.imu.size(), rig.imu.size());
  EXPECT_EQ(clean.imu.back().t_ns, rig.imu.back().t_ns);
  EXPECT_EQ(clean.groundtruth.back().t_ns, rig.groundtruth.back().t_ns);

  const Eigen::Isometry3d E = ExtrinsicError(options.rig, options.seed);
  for (int k = 0; k < 2; ++k) {
    const Eigen::Isometry3d moved = rig.cameras[k].T_b_c * clean.cameras[k].T_b_c.inverse();
    EXPECT_NEAR(AngleDeg(moved.linear()), 1.0, 1e-6);
    EXPECT_NEAR((moved.matrix() - E.matrix()).norm(), 0.0, 1e-6);
  }
  EXPECT_NEAR(E.translation().norm(), 0.015, 1e-12);
  // The truth a calibration is compared with: E and the offset, read back.
  const YAML::Node truth = YAML::LoadFile(base + "/rig/mav0/rig_truth.yaml");
  EXPECT_DOUBLE_EQ(truth["time_offset_ms"].as<double>(), 15.0);
  EXPECT_NEAR(truth["extrinsic_rotation_deg"].as<double>(), 1.0, 1e-9);
  const auto axis = truth["extrinsic_rotation_axis"].as<std::vector<double>>();
  const auto t = truth["extrinsic_translation_m"].as<std::vector<double>>();
  ASSERT_EQ(axis.size(), 3u);
  ASSERT_EQ(t.size(), 3u);
  const Eigen::Matrix3d R_truth(Eigen::AngleAxisd(1.0 * M_PI / 180.0, Eigen::Vector3d(axis[0], axis[1], axis[2])));
  EXPECT_NEAR((R_truth - E.linear()).norm(), 0.0, 1e-12);
  EXPECT_NEAR((Eigen::Vector3d(t[0], t[1], t[2]) - E.translation()).norm(), 0.0, 1e-15);
  EXPECT_DOUBLE_EQ(YAML::LoadFile(base + "/clean/mav0/rig_truth.yaml")["time_offset_ms"].as<double>(), 0.0);

  const Eigen::Isometry3d baseline_clean = clean.cameras[0].T_b_c.inverse() * clean.cameras[1].T_b_c;
  const Eigen::Isometry3d baseline_rig = rig.cameras[0].T_b_c.inverse() * rig.cameras[1].T_b_c;
  EXPECT_NEAR((baseline_clean.matrix() - baseline_rig.matrix()).norm(), 0.0, 1e-6);
}

TEST(SimulatorRigErrorsTest, ExplicitAxisAndBadOptions) {
  RigErrorOptions options;
  options.extrinsic_error_deg = 2.0;
  options.rotation_axis = Eigen::Vector3d(0, 0, 3);
  options.extrinsic_error_m = 0.03;
  options.translation_direction = Eigen::Vector3d(1, 0, 0);
  const Eigen::Isometry3d E = ExtrinsicError(options, 1);
  const Eigen::AngleAxisd rotation(E.linear());
  EXPECT_NEAR(rotation.angle() * 180.0 / M_PI, 2.0, 1e-9);
  EXPECT_NEAR(rotation.axis().z(), 1.0, 1e-9);
  EXPECT_NEAR((E.translation() - Eigen::Vector3d(0.03, 0, 0)).norm(), 0.0, 1e-12);
  options.rotation_axis = Eigen::Vector3d::Zero();
  EXPECT_THROW(CheckRigErrorOptions(options), std::invalid_argument);
  RigErrorOptions far;
  far.time_offset_ms = 2e4;
  EXPECT_THROW(CheckRigErrorOptions(far), std::invalid_argument);
}

}  // namespace
}  // namespace vio::tools
