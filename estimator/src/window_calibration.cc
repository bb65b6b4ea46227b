// Window's calibration state (window.h, docs/calibration.md): the camera-IMU
// time offset and a correction of the camera-IMU extrinsics, each one parameter
// block under a Gaussian prior that every stereo observation depends on
// through StereoCalibrationFactor.
#include <cmath>
#include <utility>

#include <glog/logging.h>

#include "vio/estimator/stereo_calibration_factor.h"
#include "vio/estimator/window.h"
#include "vio/estimator/window_covariance.h"
#include "vio/marginalization/marginalization_prior.h"

namespace vio {

void Window::EstimateTimeOffset(double mean_s, double sigma_s) {
  CHECK(!estimates_time_offset()) << "the time offset is estimated already";
  CHECK(observations_.empty()) << "EstimateTimeOffset after observations were added";
  CHECK(sigma_s > 0 && std::isfinite(mean_s)) << "time offset prior: sigma " << sigma_s << ", mean " << mean_s;
  time_offset_[0] = mean_s;
  problem_->AddParameterBlock(time_offset_, 1);
  // N(mean, sigma^2) as a linear factor r = (t_d - mean) / sigma, kept with the priors.
  std::vector<marginalization::MarginalizationPrior::Block> block = {{nullptr, {mean_s}}};
  auto factor = marginalization::MarginalizationPrior::Create(
      std::move(block), Eigen::MatrixXd::Constant(1, 1, 1.0 / sigma_s), Eigen::VectorXd::Zero(1));
  time_offset_prior_ =
      Prior{problem_->AddResidualBlock(factor.release(), nullptr, time_offset_), {BlockKey::TimeOffset()}};
  priors_.push_back(time_offset_prior_);
  HoldFirstEstimates({BlockKey::TimeOffset()});
}

void Window::EstimateExtrinsics(double sigma_rad, double sigma_m) {
  CHECK(!estimates_extrinsics()) << "the extrinsics are estimated already";
  CHECK(observations_.empty()) << "EstimateExtrinsics after observations were added";
  CHECK(sigma_rad > 0 && sigma_m > 0) << "extrinsics prior: sigmas " << sigma_rad << " rad, " << sigma_m << " m";
  problem_->AddParameterBlock(extrinsic_, 6);
  // N(0, diag(sigma_rad^2, sigma_m^2)) as a linear factor r = diag(1/sigma) c, kept with the priors.
  std::vector<marginalization::MarginalizationPrior::Block> block = {{nullptr, std::vector<double>(6, 0.0)}};
  Eigen::Matrix<double, 6, 1> information;
  information << Eigen::Vector3d::Constant(1.0 / sigma_rad), Eigen::Vector3d::Constant(1.0 / sigma_m);
  auto factor = marginalization::MarginalizationPrior::Create(std::move(block), information.asDiagonal().toDenseMatrix(),
                                                              Eigen::VectorXd::Zero(6));
  extrinsic_prior_ = Prior{problem_->AddResidualBlock(factor.release(), nullptr, extrinsic_), {BlockKey::Extrinsics()}};
  priors_.push_back(extrinsic_prior_);
  HoldFirstEstimates({BlockKey::Extrinsics()});
}

std::vector<std::pair<double*, BlockKey>> Window::KeyedCalibrationBlocks() const {
  std::vector<std::pair<double*, BlockKey>> blocks;
  if (estimates_time_offset()) blocks.emplace_back(const_cast<double*>(time_offset_), BlockKey::TimeOffset());
  if (estimates_extrinsics()) blocks.emplace_back(const_cast<double*>(extrinsic_), BlockKey::Extrinsics());
  return blocks;
}

std::vector<double*> Window::CalibrationBlocks() const {
  std::vector<double*> blocks;
  for (const auto& [block, key] : KeyedCalibrationBlocks()) blocks.push_back(block);
  return blocks;
}

std::vector<BlockKey> Window::CalibrationKeys() const {
  std::vector<BlockKey> keys;
  for (const auto& [block, key] : KeyedCalibrationBlocks()) keys.push_back(key);
  return keys;
}

RectifiedStereo Window::estimated_stereo() const {
  return estimates_extrinsics() ? CorrectedStereo(*stereo_, extrinsic_correction()) : *stereo_;
}

void Window::SetTimeOffset(double s) {
  CHECK(estimates_time_offset()) << "SetTimeOffset: the time offset is not estimated";
  time_offset_[0] = s;
}

void Window::SetTimeOffsetConstant(bool constant) {
  CHECK(estimates_time_offset()) << "SetTimeOffsetConstant: the time offset is not estimated";
  if (constant) {
    problem_->SetParameterBlockConstant(time_offset_);
  } else {
    problem_->SetParameterBlockVariable(time_offset_);
  }
}

void Window::SetCalibrationConstant(bool constant) {
  for (double* block : CalibrationBlocks()) {
    if (constant) {
      problem_->SetParameterBlockConstant(block);
    } else {
      problem_->SetParameterBlockVariable(block);
    }
  }
}

void Window::SetCameraTiming(StateId id, double applied_offset_s, const CameraMotion& motion) {
  CHECK(HasState(id)) << "camera timing of unknown state " << id.value;
  camera_timing_[id] = CameraTiming{applied_offset_s, motion};
}

std::optional<Eigen::MatrixXd> Window::CalibrationCovariance(const double* block) {
  if (problem_->IsParameterBlockConstant(block)) return std::nullopt;
  // The marginal comes from the dense reduced system over every variable state: a window's, or
  // a short sequence's final solve, not a whole recording's (batch on EuRoC: thousands of states).
  constexpr int kMaxStatesForSigma = 500;
  int variable_states = 0;
  for (const auto& [id, s] : states_) variable_states += problem_->IsParameterBlockConstant(s.pose) ? 0 : 1;
  if (variable_states > kMaxStatesForSigma) return std::nullopt;
  std::optional<Eigen::MatrixXd> covariance = MarginalCovariance(problem_.get(), Layout(), {block});
  if (!covariance || !covariance->allFinite() || !(covariance->diagonal().minCoeff() > 0)) return std::nullopt;
  return covariance;
}

std::optional<double> Window::TimeOffsetSigma() {
  if (!estimates_time_offset()) return std::nullopt;
  const std::optional<Eigen::MatrixXd> covariance = CalibrationCovariance(time_offset_);
  if (!covariance) return std::nullopt;
  return std::sqrt((*covariance)(0, 0));
}

std::optional<Eigen::Matrix<double, 6, 6>> Window::ExtrinsicCovariance() {
  if (!estimates_extrinsics()) return std::nullopt;
  const std::optional<Eigen::MatrixXd> covariance = CalibrationCovariance(extrinsic_);
  if (!covariance) return std::nullopt;
  return Eigen::Matrix<double, 6, 6>(*covariance);
}

ceres::CostFunction* Window::StereoFactorOf(StateId state_id, LandmarkId /*landmark_id*/, const Eigen::Vector3d& z_px) const {
  if (!estimates_time_offset() && !estimates_extrinsics()) return StereoFactor::Create(z_px, stereo_, model_.pixel_sigma);
  StereoCalibrationFactor::TimeOffset timing;
  const auto camera = camera_timing_.find(state_id);
  if (camera != camera_timing_.end()) {
    timing.applied_offset_s = camera->second.applied_offset_s;
    timing.motion = camera->second.motion;
  }
  return new StereoCalibrationFactor(z_px, stereo_, model_.pixel_sigma, estimates_time_offset() ? &timing : nullptr,
                                     estimates_extrinsics());
}

}  // namespace vio
