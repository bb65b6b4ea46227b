// Window's calibration state: the camera-IMU time offset (window.h,
// docs/calibration.md), one parameter block under a Gaussian prior that every
// stereo observation depends on through StereoTimeOffsetFactor.
#include <cmath>
#include <utility>

#include <glog/logging.h>

#include "vio/estimator/stereo_time_offset_factor.h"
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
  time_offset_prior_ = Prior{problem_->AddResidualBlock(factor.release(), nullptr, time_offset_), {time_offset_}};
  priors_.push_back(time_offset_prior_);
  HoldFirstEstimates({time_offset_});
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

void Window::SetCameraTiming(StateId id, double applied_offset_s, std::map<LandmarkId, Eigen::Vector3d> velocity_px_s) {
  CHECK(HasState(id)) << "camera timing of unknown state " << id.value;
  camera_timing_[id] = CameraTiming{applied_offset_s, std::move(velocity_px_s)};
}

void Window::ReleaseImageVelocities(StateId id) {
  const auto timing = camera_timing_.find(id);
  if (timing != camera_timing_.end()) std::map<LandmarkId, Eigen::Vector3d>().swap(timing->second.velocity_px_s);
}

std::optional<double> Window::TimeOffsetSigma() {
  if (!estimates_time_offset() || problem_->IsParameterBlockConstant(time_offset_)) return std::nullopt;
  // The marginal comes from the dense reduced system over every variable state: a window's, or
  // a short sequence's final solve, not a whole recording's (batch on EuRoC: thousands of states).
  constexpr int kMaxStatesForSigma = 500;
  int variable_states = 0;
  for (const auto& [id, s] : states_) variable_states += problem_->IsParameterBlockConstant(s.pose) ? 0 : 1;
  if (variable_states > kMaxStatesForSigma) return std::nullopt;
  const std::optional<Eigen::MatrixXd> covariance = MarginalCovariance(problem_.get(), Layout(), {time_offset_});
  if (!covariance || !((*covariance)(0, 0) > 0)) return std::nullopt;
  return std::sqrt((*covariance)(0, 0));
}

ceres::CostFunction* Window::StereoFactorOf(StateId state_id, LandmarkId landmark_id, const Eigen::Vector3d& z_px) const {
  if (!estimates_time_offset()) return StereoFactor::Create(z_px, stereo_, model_.pixel_sigma);
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  double applied_s = 0;
  const auto timing = camera_timing_.find(state_id);
  if (timing != camera_timing_.end()) {
    applied_s = timing->second.applied_offset_s;
    const auto v = timing->second.velocity_px_s.find(landmark_id);
    if (v != timing->second.velocity_px_s.end()) velocity = v->second;
  }
  return new StereoTimeOffsetFactor(z_px, velocity, applied_s, stereo_, model_.pixel_sigma);
}

}  // namespace vio
