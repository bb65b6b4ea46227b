#pragma once
// Pieces shared between the EuRoC reader/writer files of the tools library
// (not public API).
#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "vio/dataset/euroc_dataset.h"

namespace vio::tools {

/// imu0/data.csv rows, and in `lines` (when not null) the 1-based line each came from.
std::vector<ImuSample> ReadImuCsv(const std::string& path, std::vector<int>* lines);

/// camN/data.csv rows, and in `lines` the 1-based line each row came from.
std::vector<CameraFrame> ReadCameraCsv(const std::string& path, std::vector<int>* lines);

/// Throws "<csv_path>:<line>: listed image missing: <image_dir>/<file>" for the
/// first frame whose image file is not in `image_dir`.
void CheckImagesExist(const std::string& csv_path, const std::vector<CameraFrame>& frames,
                      const std::vector<int>& lines, const std::string& image_dir);

/// Parses an EuRoC/OpenCV-style YAML file: a leading `%YAML:1.0` directive
/// (which yaml-cpp rejects) is blanked first, keeping line numbers. Throws
/// DatasetError "<path>:<line>: ..." on a syntax error, "<path>: cannot open".
YAML::Node LoadSensorYaml(const std::string& path);

/// mav0/body.yaml as in EuRoC ("comment: ...").
void WriteBodyYaml(const std::string& path);

/// state_groundtruth_estimate0/sensor.yaml as in EuRoC (identity T_BS).
void WriteGroundTruthSensorYaml(const std::string& path);

}  // namespace vio::tools
