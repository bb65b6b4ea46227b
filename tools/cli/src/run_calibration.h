#pragma once
// `vio run`'s online calibration output (docs/calibration.md): summary.json's
// calibration block and the calibration folder with the estimated rig.
#include <optional>
#include <string>

#include "vio/cli/run.h"
#include "vio/dataset/euroc_dataset.h"
#include "vio/estimator/estimator.h"

namespace vio::tools {

/// The calibration the run ends with: the time offset (the calibration file's plus the estimate)
/// and the extrinsics' correction, with their sigmas.
void RecordCalibration(const EurocDataset& dataset, Estimator& estimator,
                       const std::optional<Estimator::TimeOffsetSearchReport>& search, CalibrationReport* calibration);

/// Writes `dir`/mav0/{cam0,cam1,imu0}/sensor.yaml: the dataset's calibration with both cameras'
/// T_BS moved rigidly by the window's extrinsics correction (the baseline kept); a folder
/// --calibration takes.
void WriteCalibration(const EurocDataset& dataset, const Window& window, const std::string& dir);

}  // namespace vio::tools
