#include "run_calibration.h"

#include <cmath>
#include <filesystem>

#include <Eigen/Eigenvalues>

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

namespace {

void RecordRigRotationSearch(const Estimator::RigRotationSearchReport& search, CalibrationReport* calibration) {
  calibration->rig_rotation_search_deg = search.rotation_vector * (180.0 / M_PI);
  calibration->rig_rotation_search_sigma_deg = search.sigma_rad * (180.0 / M_PI);
  calibration->rig_rotation_search_excited = search.excited;
  calibration->rig_rotation_search_restarted = search.restart;
}

}  // namespace

void RecordCalibration(const EurocDataset& dataset, Estimator& estimator, const InitSearches& searches,
                       CalibrationReport* calibration) {
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
  const Eigen::Matrix<double, 6, 1> c = window.extrinsic_correction();
  // In the body: the rig turned by Exp(R_b_cl dtheta) (R_b_cl Exp(dtheta) = Exp(R_b_cl dtheta) R_b_cl).
  // The search's turn Q first (the window's rig is sensor.yaml's turned by it): Exp(R_b_cl dtheta) Q.
  const Eigen::Matrix3d turn = so3::Exp(window.stereo().T_b_cl.linear() * c.head<3>()) * searches.RigTurn();
  calibration->extrinsics_rotation_deg = so3::Log(turn) * (180.0 / M_PI);
  if (searches.rig_rotation) RecordRigRotationSearch(*searches.rig_rotation, calibration);
  calibration->extrinsics_translation_m = c.tail<3>();
  if (const std::optional<Eigen::Matrix<double, 6, 6>> covariance = estimator.ExtrinsicCovariance()) {
    const auto largest_sigma = [](const Eigen::Matrix3d& block) {
      return std::sqrt(Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(block).eigenvalues().maxCoeff());
    };
    const Eigen::Matrix3d R_b_cl = window.stereo().T_b_cl.linear();
    calibration->extrinsics_rotation_sigma_deg =
        largest_sigma(R_b_cl * covariance->topLeftCorner<3, 3>() * R_b_cl.transpose()) * (180.0 / M_PI);
    calibration->extrinsics_translation_sigma_m = largest_sigma(covariance->bottomRightCorner<3, 3>());
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
