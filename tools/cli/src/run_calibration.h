#pragma once
// `vio run`'s online calibration output (docs/calibration.md): summary.json's
// calibration block and the calibration folder with the estimated rig.
#include <optional>
#include <string>

#include "vio/cli/run.h"
#include "vio/dataset/euroc_dataset.h"
#include "vio/estimator/estimator.h"

namespace vio::tools {

/// What the searches at initialization found (Estimator::time_offset_search, rig_rotation_search).
struct InitSearches {
  std::optional<Estimator::TimeOffsetSearchReport> time_offset;
  std::optional<Estimator::RigRotationSearchReport> rig_rotation;
  /// Whether either asked to start the run again.
  bool restart() const {
    return (time_offset && time_offset->restart) || (rig_rotation && rig_rotation->restart);
  }
  /// The turn of sensor.yaml's cameras in the body the rig rotation search asked for (else identity).
  Eigen::Matrix3d RigTurn() const;
};

/// `rig`'s left camera turned in the body by the rig rotation search's result when it asked for it
/// (the run's second pass), else `rig` unchanged.
RectifiedStereo TurnedRig(const RectifiedStereo& rig, const InitSearches& searches);

/// The request of the pass after a search asked to start again: both searches off, the time offset
/// prior's mean at the found offset; the rig's turn is TurnedRig's, and `estimate_turned` estimates the
/// extrinsics online from there (without the extrinsics probe, which decides that otherwise).
RunRequest AfterSearches(const RunRequest& request, const InitSearches& searches, bool estimate_turned);

/// The largest standard deviation over directions of a 3x3 covariance.
double LargestSigma(const Eigen::Matrix3d& covariance);

/// The calibration the run ends with: the time offset (the calibration file's plus the estimate)
/// and the extrinsics' change from `given` (sensor.yaml's rectified left camera in the body) to the
/// window's estimated rig (the searches' turn, the probe's correction and the window's), with their sigmas.
void RecordCalibration(const EurocDataset& dataset, Estimator& estimator, const InitSearches& searches,
                       const Eigen::Isometry3d& given, CalibrationReport* calibration);

/// Writes `dir`/mav0/{cam0,cam1,imu0}/sensor.yaml: the dataset's calibration with both cameras'
/// T_BS moved rigidly from `given` (sensor.yaml's rectified left camera in the body) to the window's
/// estimated rig (the baseline kept); a folder --calibration takes.
void WriteCalibration(const EurocDataset& dataset, const Window& window, const Eigen::Isometry3d& given,
                      const std::string& dir);

}  // namespace vio::tools
