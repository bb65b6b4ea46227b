#pragma once
// EuRoC ASL dataset folders in memory, and their reader and writer.
//
// A sequence folder holds mav0/ with imu0/, cam0/, cam1/,
// state_groundtruth_estimate0/ (data.csv with 17 columns, or TUM text
// groundtruth_tum.txt), sensor.yaml files (with their `%YAML:1.0` directive),
// body.yaml, and this project's extension features0/data.csv:
//   #timestamp [ns],camera,feature_id,u [px],v [px]
// one row per observation, camera 0 or 1, distorted pixels as the camera sees
// them, one feature_id per landmark across both cameras and all times.
//
// Every reader error is a DatasetError whose message names the file and the
// 1-based line: "<file>:<line>: <what>" ("<file>: cannot open ..." for a
// missing file). Readers accept CRLF or LF, '#' comment lines and blank lines;
// they reject wrong column counts, non-numeric fields, NaN/inf, non-increasing
// or duplicated timestamps and empty data files (features excepted), never
// dropping a row. Writers print doubles in their shortest round-trip form, so
// Read*(Write*(x)) == x exactly.
#include <optional>
#include <stdexcept>
#include <memory>
#include <string>
#include <vector>

#include "vio/estimator/types.h"

namespace vio::tools {

/// Bad input: the message names the file and line.
class DatasetError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Ground truth at one instant (body = IMU frame, in world).
struct GroundTruthState {
  Timestamp t_ns = 0;
  Eigen::Vector3d p_w_b = Eigen::Vector3d::Zero();              ///< [m]
  Eigen::Quaterniond q_w_b = Eigen::Quaterniond::Identity();    ///< Hamilton, unit (normalised on read)
  Eigen::Vector3d v_w_b = Eigen::Vector3d::Zero();              ///< [m/s]; zero from TUM text
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();          ///< [rad/s]; zero from TUM text
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();         ///< [m/s^2]; zero from TUM text
  bool has_velocity_and_biases = true;                          ///< false when read from TUM text (poses only)
};

/// One row of camN/data.csv: the frame stamp and the image file it names.
struct CameraFrame {
  Timestamp t_ns = 0;
  std::string filename;  ///< relative to camN/data/
};

/// One row of features0/data.csv.
struct FeatureObservation {
  Timestamp t_ns = 0;
  int camera = 0;                                   ///< 0 (left) or 1 (right)
  std::int64_t feature_id = 0;                      ///< one id per landmark
  Eigen::Vector2d uv_px = Eigen::Vector2d::Zero();  ///< distorted pixels
};

/// A warning about IMU timing: gaps longer than 3 nominal sample periods.
struct ImuGapReport {
  int count = 0;             ///< number of gaps
  Timestamp longest_ns = 0;  ///< longest gap [ns]
};

struct Ros2ImageIndex;  // ros2_dataset.cc

/// What a sequence folder holds. Optional parts are empty when absent.
struct EurocDataset {
  std::string root;  ///< the folder holding mav0/
  ImuCalibration imu_calibration;
  std::vector<ImuSample> imu;
  std::string imu_file;        ///< the imu0/data.csv read (empty when not read from a file)
  std::vector<int> imu_lines;  ///< 1-based line of each sample in imu_file (empty when not read)
  ImuGapReport imu_gaps;
  CameraCalibration cameras[2];
  /// The camera clock against the IMU's: an image stamped t was taken at IMU time
  /// t - camera_time_offset_ns (Kalibr's timeshift_cam_imu is its negative; EuRoC's sensor.yaml has
  /// none: 0). `vio run` moves the frames onto the IMU's clock by it; the prior of an online estimate.
  Timestamp camera_time_offset_ns = 0;
  std::vector<CameraFrame> frames[2];  ///< cam0, cam1 data.csv rows
  bool has_images = false;             ///< images were checked and every listed one exists
  /// A ROS bag holding the images as messages of `image_topics` (rosbag_dataset.h); empty: the
  /// images are the files of mav0/camN/data/.
  std::string image_bag;
  std::string image_topics[2];
  /// Where ReadRos2Bag found each image message of image_bag (ros2_dataset.h); null otherwise.
  std::shared_ptr<const Ros2ImageIndex> ros2_images;
  std::vector<GroundTruthState> groundtruth;
  std::vector<FeatureObservation> features;  ///< features0, sorted by (t, camera, id)
  /// features0/data.csv when it has rows and is not kept (EurocReadOptions::stream_features)
  std::string features_file;
};

/// What to read; parts not asked for are left empty.
struct EurocReadOptions {
  bool read_imu = true;
  bool read_cameras = true;       ///< calibration and data.csv of cam0/cam1
  /// When cam0/data/ or cam1/data/ holds any file: error naming the first
  /// listed image that is missing (else, as in image-less sequences, no check).
  bool check_images = true;
  bool read_groundtruth = true;
  bool read_features = true;      ///< features0/data.csv when present
  /// With read_features: features0 is not kept (`features` stays empty,
  /// `features_file` names it when it has rows); only its header and first
  /// timestamp's rows are checked here, the rest by the FeatureCsvStream that reads it.
  bool stream_features = false;
};

/// Reads an ASL sequence folder (the one holding mav0/, or mav0/ itself).
/// imu0/ and cam0/, cam1/ (sensor.yaml, data.csv) are required when asked for;
/// ground truth is state_groundtruth_estimate0/data.csv, else its
/// groundtruth_tum.txt, else empty; features0/data.csv is optional. IMU gaps
/// are stored in `imu_gaps` and LOG(WARNING)ed. Throws DatasetError naming
/// file and line on bad input.
EurocDataset ReadEuroc(const std::string& root, const EurocReadOptions& options = {});

/// Replaces the camera and IMU calibration of `dataset` with those of the ASL
/// folder `folder` (its mav0/{cam0,cam1,imu0}/sensor.yaml; no data.csv needed).
void ApplyCalibrationFrom(const std::string& folder, EurocDataset* dataset);

/// Writes a whole ASL folder (creates directories): imu0, cam0/cam1 (sensor.yaml,
/// data.csv; images are the caller's), state_groundtruth_estimate0, body.yaml,
/// and features0 when `dataset.features` is not empty. Deterministic output.
/// Ground truth and features files of a previous dataset in the folder are
/// removed when `dataset` has none, so ReadEuroc(root) gives `dataset` back.
void WriteEuroc(const EurocDataset& dataset, const std::string& root);

// Single-file readers and writers (the building blocks of the above).
std::vector<ImuSample> ReadImuCsv(const std::string& path);
void WriteImuCsv(const std::vector<ImuSample>& imu, const std::string& path);
std::vector<GroundTruthState> ReadGroundTruthCsv(const std::string& path);  ///< 17 columns
std::vector<GroundTruthState> ReadTumTrajectory(const std::string& path);   ///< t x y z qx qy qz qw
void WriteGroundTruthCsv(const std::vector<GroundTruthState>& gt, const std::string& path);
void WriteTumTrajectory(const std::vector<GroundTruthState>& poses, const std::string& path);
/// WriteTumTrajectory's first line, and its line of one pose ("t x y z qx qy qz qw\n"; throws
/// DatasetError naming `path` for a non-finite value): a file can be written a pose at a time.
inline constexpr char kTumTrajectoryHeader[] = "# timestamp[s] tx ty tz qx qy qz qw\n";
std::string TumTrajectoryLine(const GroundTruthState& pose, const std::string& path);
std::vector<CameraFrame> ReadCameraCsv(const std::string& path);
void WriteCameraCsv(const std::vector<CameraFrame>& frames, const std::string& path);
/// Rows sorted by (t, camera, feature_id); an empty table (header only) is allowed.
std::vector<FeatureObservation> ReadFeaturesCsv(const std::string& path);
void WriteFeaturesCsv(const std::vector<FeatureObservation>& features, const std::string& path);

/// features0/data.csv one timestamp at a time (the file is sorted by time),
/// with ReadFeaturesCsv's checks, never holding the whole table.
class FeatureCsvStream {
 public:
  /// Throws DatasetError when the file cannot be opened.
  explicit FeatureCsvStream(const std::string& path);
  ~FeatureCsvStream();
  FeatureCsvStream(const FeatureCsvStream&) = delete;
  FeatureCsvStream& operator=(const FeatureCsvStream&) = delete;
  /// The next timestamp's observations sorted by (camera, feature_id); false
  /// at the end. Throws DatasetError "<path>:<line>: ..." on a malformed row.
  bool Next(std::vector<FeatureObservation>* group);

 private:
  struct Reader;
  std::unique_ptr<Reader> reader_;
};
CameraCalibration ReadCameraYaml(const std::string& path);
void WriteCameraYaml(const CameraCalibration& camera, const std::string& path);
ImuCalibration ReadImuYaml(const std::string& path);
void WriteImuYaml(const ImuCalibration& imu, const std::string& path);

/// Gaps in IMU timing longer than 3 nominal periods (1 / rate_hz); rate_hz > 0.
ImuGapReport FindImuGaps(const std::vector<ImuSample>& imu, double rate_hz);

}  // namespace vio::tools
