#pragma once
// The configuration of one `vio run`: built-in defaults, then the run's YAML
// file, then command-line flags of the same names.
#include <string>

#include "vio/estimator/estimator_options.h"
#include "vio/frontend/frontend_options.h"
#include "vio/cli/options_registry.h"
#include "vio/dataset/rosbag_dataset.h"

namespace vio::tools {

/// Where calibration comes from.
struct CalibrationOptions {
  /// Folder holding mav0/{cam0,cam1,imu0}/sensor.yaml, or Kalibr's camchain-imucam.yaml; empty = the
  /// dataset's own.
  std::string calibration;
  /// Kalibr's imu.yaml for a camchain; empty = imu.yaml (or imu-NAME.yaml) beside it.
  std::string calibration_imu;

  template <class V>
  void Visit(V& v) {
    v("calibration", calibration,
      "folder whose mav0/{cam0,cam1,imu0}/sensor.yaml calibrate the run, or Kalibr's camchain-imucam.yaml "
      "(T_cam_imu, intrinsics, distortion, timeshift_cam_imu); empty = the dataset's own (required for a ROS 1 bag or ROS 2 recording)");
    v("calibration_imu", calibration_imu,
      "with a Kalibr camchain as --calibration: Kalibr's imu.yaml (noise densities, random walks, update_rate); "
      "empty = imu.yaml or imu-NAME.yaml beside camchain-imucam-NAME.yaml");
  }
};

struct RunConfig {
  CalibrationOptions calibration;
  BagTopics bag;  ///< topics of a ROS 1 bag or ROS 2 recording given as --dataset
  FrontendOptions frontend;
  EstimatorOptions estimator;
};

/// Binds every field of `config` to `registry` under its YAML section.
void BindRunConfig(RunConfig* config, OptionRegistry* registry);

/// Registers one command-line flag per RunConfig field (defaults: built-in).
/// Call once, before gflags parses the command line.
void RegisterRunConfigFlags();

/// Defaults, then `yaml_path` (when not empty), then the flags given on the
/// command line. Throws ConfigError on an unknown key or bad value.
RunConfig LoadRunConfig(const std::string& yaml_path);

/// Checks what no single option's range can: combinations (the MSCKF needs a
/// window of at least 2). Throws ConfigError naming the option.
void ValidateRunConfig(const RunConfig& config);

/// The effective configuration as YAML (written next to every run's results).
std::string RunConfigToYaml(RunConfig config);

}  // namespace vio::tools
