// ReadEuroc / WriteEuroc: a whole ASL sequence folder from and to its files.
#include "vio/dataset/euroc_dataset.h"

#include <glog/logging.h>

#include <filesystem>

#include "euroc_internal.h"

namespace vio::tools {
namespace {

namespace fs = std::filesystem;

struct SequenceFolders {
  std::string root;  ///< the folder holding mav0/
  std::string mav0;
};

std::string WithoutTrailingSlash(std::string path) {
  while (path.size() > 1 && path.back() == '/') path.pop_back();
  return path;
}

SequenceFolders FindSequenceFolders(const std::string& root_or_mav0) {
  const std::string path = WithoutTrailingSlash(root_or_mav0);
  std::error_code ec;
  if (fs::is_directory(path + "/mav0", ec)) return {path, path + "/mav0"};
  if (fs::path(path).filename() == "mav0" && fs::is_directory(path, ec)) {
    const std::string parent = fs::path(path).parent_path().string();
    return {parent.empty() ? "." : parent, path};
  }
  throw DatasetError(path + ": missing mav0/ (not an ASL sequence folder)");
}

std::string CameraFolder(const std::string& mav0, int camera) {
  return mav0 + "/cam" + std::to_string(camera);
}

bool HoldsAnyFile(const std::string& folder) {
  std::error_code ec;
  return fs::is_directory(folder, ec) &&
         fs::directory_iterator(folder, ec) != fs::directory_iterator();
}

void ReadImu(const std::string& mav0, EurocDataset* dataset) {
  const std::string csv = mav0 + "/imu0/data.csv";
  dataset->imu_calibration = ReadImuYaml(mav0 + "/imu0/sensor.yaml");
  dataset->imu_file = csv;
  dataset->imu = ReadImuCsv(csv, &dataset->imu_lines);
  dataset->imu_gaps = FindImuGaps(dataset->imu, dataset->imu_calibration.rate_hz);
  if (dataset->imu_gaps.count > 0) {
    LOG(WARNING) << csv << ": " << dataset->imu_gaps.count
                 << " gaps longer than 3 nominal IMU periods; longest "
                 << NanosToSeconds(dataset->imu_gaps.longest_ns) * 1e3 << " ms";
  }
}

void ReadCameras(const std::string& mav0, bool check_images, EurocDataset* dataset) {
  std::vector<int> lines[2];
  for (int i = 0; i < 2; ++i) {
    dataset->cameras[i] = ReadCameraYaml(CameraFolder(mav0, i) + "/sensor.yaml");
    dataset->frames[i] = ReadCameraCsv(CameraFolder(mav0, i) + "/data.csv", &lines[i]);
  }
  const bool images_present = HoldsAnyFile(CameraFolder(mav0, 0) + "/data") ||
                              HoldsAnyFile(CameraFolder(mav0, 1) + "/data");
  if (!check_images || !images_present) return;
  for (int i = 0; i < 2; ++i) {
    CheckImagesExist(CameraFolder(mav0, i) + "/data.csv", dataset->frames[i], lines[i],
                     CameraFolder(mav0, i) + "/data");
  }
  dataset->has_images = true;
}

std::vector<GroundTruthState> ReadGroundTruth(const std::string& mav0) {
  const std::string folder = mav0 + "/state_groundtruth_estimate0";
  std::error_code ec;
  if (fs::exists(folder + "/data.csv", ec)) return ReadGroundTruthCsv(folder + "/data.csv");
  if (fs::exists(folder + "/groundtruth_tum.txt", ec)) {
    return ReadTumTrajectory(folder + "/groundtruth_tum.txt");
  }
  LOG(INFO) << mav0 << ": no ground truth (" << folder << "/data.csv or groundtruth_tum.txt)";
  return {};
}

void MakeFolder(const std::string& folder) {
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec) throw DatasetError(folder + ": cannot create folder: " + ec.message());
}

// Removes a file of a part the dataset does not have, so that reading the
// folder back gives exactly the dataset written.
void RemoveStale(const std::string& path) {
  std::error_code ec;
  fs::remove(path, ec);
  if (ec) throw DatasetError(path + ": cannot remove stale file: " + ec.message());
}

void WriteGroundTruth(const std::vector<GroundTruthState>& gt, const std::string& mav0) {
  const std::string folder = mav0 + "/state_groundtruth_estimate0";
  if (gt.empty()) {
    RemoveStale(folder + "/data.csv");
    RemoveStale(folder + "/groundtruth_tum.txt");
    return;
  }
  WriteGroundTruthSensorYaml(folder + "/sensor.yaml");
  WriteGroundTruthCsv(gt, folder + "/data.csv");
}

}  // namespace

EurocDataset ReadEuroc(const std::string& root, const EurocReadOptions& options) {
  const SequenceFolders folders = FindSequenceFolders(root);
  EurocDataset dataset;
  dataset.root = folders.root;
  if (options.read_imu) ReadImu(folders.mav0, &dataset);
  if (options.read_cameras) ReadCameras(folders.mav0, options.check_images, &dataset);
  if (options.read_groundtruth) dataset.groundtruth = ReadGroundTruth(folders.mav0);
  std::error_code ec;
  const std::string features = folders.mav0 + "/features0/data.csv";
  if (options.read_features && fs::exists(features, ec)) {
    if (options.stream_features) {
      // The header and the first timestamp's rows only: the run's stream checks the others as it reads them.
      FeatureCsvStream stream(features);
      std::vector<FeatureObservation> group;
      if (stream.Next(&group)) dataset.features_file = features;
    } else {
      dataset.features = ReadFeaturesCsv(features);
    }
  }
  return dataset;
}

void ApplyCalibrationFrom(const std::string& folder, EurocDataset* dataset) {
  // Only the sensor.yaml files: a calibration folder (as `vio run` writes one) needs no frames.
  const std::string mav0 = FindSequenceFolders(folder).mav0;
  for (int i = 0; i < 2; ++i) dataset->cameras[i] = ReadCameraYaml(CameraFolder(mav0, i) + "/sensor.yaml");
  dataset->imu_calibration = ReadImuYaml(mav0 + "/imu0/sensor.yaml");
}

void WriteEuroc(const EurocDataset& dataset, const std::string& root) {
  const std::string mav0 = WithoutTrailingSlash(root) + "/mav0";
  WriteImuYaml(dataset.imu_calibration, mav0 + "/imu0/sensor.yaml");
  WriteImuCsv(dataset.imu, mav0 + "/imu0/data.csv");
  for (int i = 0; i < 2; ++i) {
    WriteCameraYaml(dataset.cameras[i], CameraFolder(mav0, i) + "/sensor.yaml");
    WriteCameraCsv(dataset.frames[i], CameraFolder(mav0, i) + "/data.csv");
    MakeFolder(CameraFolder(mav0, i) + "/data");
  }
  WriteBodyYaml(mav0 + "/body.yaml");
  WriteGroundTruth(dataset.groundtruth, mav0);
  if (dataset.features.empty()) {
    RemoveStale(mav0 + "/features0/data.csv");
  } else {
    WriteFeaturesCsv(dataset.features, mav0 + "/features0/data.csv");
  }
}

}  // namespace vio::tools
