#include "run_calibration.h"

#include <cmath>
#include <filesystem>

#include <Eigen/Eigenvalues>
#include <glog/logging.h>

#include "vio/estimator/so3.h"

namespace vio::tools {

Eigen::Matrix3d InitSearches::RigTurn() const {
  if (!rig_rotation || !rig_rotation->restart) return Eigen::Matrix3d::Identity();
  return so3::Exp(rig_rotation->rotation_vector);
}

RectifiedStereo TurnedRig(const RectifiedStereo& rig, const InitSearches& searches) {
  RectifiedStereo turned = rig;
  if (searches.rig_rotation && searches.rig_rotation->restart) {
    turned.T_b_cl.linear() = searches.RigTurn() * rig.T_b_cl.linear();
  }
  return turned;
}

RunRequest AfterSearches(const RunRequest& request, const InitSearches& searches, bool estimate_turned) {
  RunRequest again = request;
  ModelOptions& model = again.config.estimator.model;
  model.time_offset_search_ms = 0;
  model.extrinsics_rotation_search = false;
  if (searches.time_offset && searches.time_offset->restart) {
    const Estimator::TimeOffsetSearchReport& search = *searches.time_offset;
    model.time_offset_prior_mean_ms = 1e3 * search.offset_s;
    LOG(WARNING) << "the camera-IMU time offset is " << 1e3 * search.offset_s << " +- " << 1e3 * search.sigma_s
                 << " ms, beyond its prior (time_offset_prior_mean_ms " << request.config.estimator.model.time_offset_prior_mean_ms
                 << " +- " << request.config.estimator.model.time_offset_prior_sigma_ms
                 << " ms): starting again from the first frame with the prior's mean there";
  }
  if (searches.rig_rotation && searches.rig_rotation->restart) {
    const Estimator::RigRotationSearchReport& search = *searches.rig_rotation;
    // The search is within about a degree (the gyro's own axes against the accelerometer's): the
    // online correction (or the probe) takes it from there.
    if (estimate_turned) model.estimate_extrinsics = true;
    LOG(WARNING) << "the cameras' rotation in the body is off by " << search.rotation_vector.norm() * 180.0 / M_PI
                 << " +- " << search.sigma_rad * 180.0 / M_PI << " deg from sensor.yaml's (beyond "
                 << "2 extrinsics_prior_sigma_deg): starting again from the first frame with the cameras turned by it"
                 << (estimate_turned ? " and the extrinsics estimated online" : "");
  }
  return again;
}

double LargestSigma(const Eigen::Matrix3d& covariance) {
  return std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance).eigenvalues().maxCoeff());
}

namespace {

void RecordRigRotationSearch(const Estimator::RigRotationSearchReport& search, CalibrationReport* calibration) {
  calibration->rig_rotation_search_deg = search.rotation_vector * (180.0 / M_PI);
  calibration->rig_rotation_search_sigma_deg = search.sigma_rad * (180.0 / M_PI);
  calibration->rig_rotation_search_excited = search.excited;
  calibration->rig_rotation_search_restarted = search.restart;
}

}  // namespace

void RecordCalibration(const EurocDataset& dataset, Estimator& estimator, const InitSearches& searches,
                       const Eigen::Isometry3d& given, CalibrationReport* calibration) {
  const std::optional<Estimator::TimeOffsetSearchReport>& search = searches.time_offset;
  calibration->time_offset_estimated = estimator.window().estimates_time_offset();
  calibration->time_offset_calibration_ms = 1e-6 * static_cast<double>(dataset.camera_time_offset_ns);
  calibration->time_offset_ms = calibration->time_offset_calibration_ms + 1e3 * estimator.time_offset_s();
  if (const std::optional<double> sigma = estimator.TimeOffsetSigma()) calibration->time_offset_sigma_ms = 1e3 * *sigma;
  if (search) {
    calibration->time_offset_search_ms = calibration->time_offset_calibration_ms + 1e3 * search->offset_s;
    calibration->time_offset_search_sigma_ms = 1e3 * search->sigma_s;
    calibration->time_offset_search_restarted = search->restart;
  }
  const Window& window = estimator.window();
  calibration->extrinsics_estimated = window.estimates_extrinsics();
  // The body's turn from the given rig to the estimated one, and the left camera's move.
  const Eigen::Isometry3d estimated = window.estimated_stereo().T_b_cl;
  const Eigen::Matrix3d turn = estimated.linear() == given.linear() ? Eigen::Matrix3d::Identity()
                                                                      : Eigen::Matrix3d(estimated.linear() * given.linear().transpose());
  calibration->extrinsics_rotation_deg = so3::Log(turn) * (180.0 / M_PI);
  calibration->extrinsics_translation_m = estimated.translation() - given.translation();
  if (searches.rig_rotation) RecordRigRotationSearch(*searches.rig_rotation, calibration);
  if (const std::optional<Eigen::Matrix<double, 6, 6>> covariance = estimator.ExtrinsicCovariance()) {
    const Eigen::Matrix3d R_b_cl = window.stereo().T_b_cl.linear();
    calibration->extrinsics_rotation_sigma_deg =
        LargestSigma(R_b_cl * covariance->topLeftCorner<3, 3>() * R_b_cl.transpose()) * (180.0 / M_PI);
    calibration->extrinsics_translation_sigma_m = LargestSigma(covariance->bottomRightCorner<3, 3>());
  }
}

void WriteCalibration(const EurocDataset& dataset, const Window& window, const Eigen::Isometry3d& given,
                      const std::string& dir) {
  const std::string mav0 = dir + "/mav0";
  // M moves the rectified left camera from the given rig to the estimated one; the raw cameras
  // sit rigidly on it: T_b_c' = M T_b_c.
  const Eigen::Isometry3d M = window.estimated_stereo().T_b_cl * given.inverse();
  for (int i = 0; i < 2; ++i) {
    CameraCalibration camera = dataset.cameras[i];
    camera.T_b_c = M * camera.T_b_c;
    const std::string folder = mav0 + "/cam" + std::to_string(i);
    std::filesystem::create_directories(folder);
    WriteCameraYaml(camera, folder + "/sensor.yaml");
  }
  std::filesystem::create_directories(mav0 + "/imu0");
  WriteImuYaml(dataset.imu_calibration, mav0 + "/imu0/sensor.yaml");
}

}  // namespace vio::tools
