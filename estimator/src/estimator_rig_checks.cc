// Estimator's checks of the rig against physics (rig_checks.h, docs/bad-input.md), the coarse
// camera-IMU time offset search and the rig rotation search at initialization (time_offset_search.h,
// rig_rotation_search.h, docs/calibration.md): each compares the gyro's rotation with the stereo
// camera's over frame pairs.
#include <cmath>
#include <iomanip>
#include <sstream>

#include <glog/logging.h>

#include "vio/estimator/estimator.h"
#include "vio/estimator/so3.h"
#include "vio/estimator/stereo_motion.h"

namespace vio {
namespace {

// Implausible dynamic initializations in a row that make an input problem (one alone can be a
// window the motion does not determine).
constexpr int kImplausibleInits = 3;
// Frame time after which a search that has not seen enough rotation gives up (the offset is then
// estimated from its prior, as without the search) [s].
constexpr double kMaxSearchS = 30.0;
// A search result at its range's end names clocks beyond it only when it fits this much better
// than the prior's mean (TimeOffsetSearch::Result::improvement: 25 is 5 sigmas).
constexpr double kBeyondRangeImprovement = 25.0;
// A search result lies beyond the prior when this many of the prior's sigmas and of its own away.
constexpr double kFarPriorSigmas = 2.0;
constexpr double kFarSearchSigmas = 3.0;
// The rig rotation search tells the rotation only when its largest sigma is below this (a motion
// that turns about one axis leaves the rotation about it unknown) [rad] (0.5 deg).
constexpr double kMaxRigSearchSigmaRad = 0.5 * M_PI / 180.0;
// The rig rotation search's frame pairs: each frame with the oldest of the last this many seconds
// (at least half of it back) [s].
constexpr double kRigPairSpanS = 1.0;

std::string Milliseconds(double s) {
  std::ostringstream os;
  os << std::fixed << std::setprecision(1) << 1e3 * s << " ms";
  return os.str();
}

}  // namespace

std::string Estimator::CheckDynamicResult(const DynamicInitResult& result) {
  std::string implausible = CheckFreeGravity(result.free_gravity_norm, rig_limits_);
  if (implausible.empty() && result.state) {
    implausible = CheckBiases(result.state->gyro_bias, result.state->accel_bias, rig_limits_, "dynamic initialization");
  }
  implausible_inits_ = implausible.empty() ? 0 : implausible_inits_ + 1;
  if (implausible_inits_ >= kImplausibleInits) input_problem_ = implausible;
  return implausible;
}

void Estimator::StartTimeOffsetSearch() {
  if (!window_.estimates_time_offset() || options_.model.time_offset_search_ms <= 0) return;
  TimeOffsetSearch::Options search;
  search.max_offset_s = 1e-3 * options_.model.time_offset_search_ms;
  offset_search_.emplace(search);
}

// Each frame is paired with the oldest of the last RotationCheck::kPairSpanS (at least half of it
// back); the gyro's rotation between them is its readings integrated as a vector (IntegratedGyro).
// The search takes the pairs at their camera stamps less the prior's mean: one base for every pair
// while the estimate moves.
void Estimator::CheckRotation(const StereoFrame& frame, Timestamp search_t_ns) {
  if (rig_search_) AddRigSearchFrame(frame);
  const bool checking = !rotation_check_.decided();
  if (!checking && !offset_search_) return;
  if (offset_search_ && offset_search_start_ns_ < 0) offset_search_start_ns_ = frame.t_ns;
  Eigen::Vector3d gyro_sum = Eigen::Vector3d::Zero();
  if (!rotation_frames_.empty()) {
    const RotationCheckFrame& last = rotation_frames_.back();
    const bool covered = !imu_.empty() && imu_.front().t_ns <= last.frame.t_ns && imu_.back().t_ns >= frame.t_ns;
    if (covered && last.frame.t_ns < frame.t_ns) {
      gyro_sum = last.gyro_sum + IntegratedGyro(imu_, last.frame.t_ns, frame.t_ns);
    } else {
      rotation_frames_.clear();
    }
  }
  rotation_frames_.push_back({frame, gyro_sum, search_t_ns});
  const Timestamp span_ns = SecondsToNanos(RotationCheck::kPairSpanS);
  // Spans by the camera's stamps: the frames' IMU times move with the offset's estimate.
  while (rotation_frames_.front().search_t_ns < search_t_ns - span_ns) rotation_frames_.pop_front();
  const RotationCheckFrame& first = rotation_frames_.front();
  if (2 * (search_t_ns - first.search_t_ns) < span_ns) return;
  const std::optional<StereoRelativePose> camera =
      RelativeStereoPose(first.frame, frame, window_.stereo(), options_.model, options_.init.dynamic_min_landmarks);
  if (!camera) return;
  const Eigen::Vector3d theta_camera = so3::Log(Eigen::Matrix3d(camera->T_a_b.linear()));
  if (checking) {
    rotation_check_.Add(rotation_frames_.back().gyro_sum - first.gyro_sum, theta_camera);
    if (rotation_check_.decided() && !rotation_check_.problem().empty()) input_problem_ = rotation_check_.problem();
  }
  if (offset_search_) {
    offset_search_->AddPair(first.search_t_ns, search_t_ns, theta_camera);
    if (offset_search_->result()) {
      ApplyTimeOffsetSearch(*offset_search_->result());
    } else if (frame.t_ns - offset_search_start_ns_ > SecondsToNanos(kMaxSearchS)) {
      LOG(INFO) << "time offset search: too little rotation in the first " << kMaxSearchS << " s";
      offset_search_.reset();
    }
  }
  if (rotation_check_.decided() && !offset_search_) rotation_frames_.clear();
}

// Pairs kRigPairSpanS apart (a 3D-3D fit's rotation error is about the same at any span, the
// rotation grows with it), the gyro's rotation composed over each.
void Estimator::AddRigSearchFrame(const StereoFrame& frame) {
  if (rig_search_start_ns_ < 0) rig_search_start_ns_ = frame.t_ns;
  Eigen::Quaterniond q_gyro = Eigen::Quaterniond::Identity();
  if (!rig_frames_.empty()) {
    const RigSearchFrame& last = rig_frames_.back();
    const bool covered = !imu_.empty() && imu_.front().t_ns <= last.frame.t_ns && imu_.back().t_ns >= frame.t_ns;
    if (covered && last.frame.t_ns < frame.t_ns) {
      q_gyro = last.q_gyro * IntegratedRotation(imu_, last.frame.t_ns, frame.t_ns);
    } else {
      rig_frames_.clear();
    }
  }
  rig_frames_.push_back({frame, q_gyro});
  const Timestamp span_ns = SecondsToNanos(kRigPairSpanS);
  while (rig_frames_.front().frame.t_ns < frame.t_ns - span_ns) rig_frames_.pop_front();
  const RigSearchFrame& first = rig_frames_.front();
  if (2 * (frame.t_ns - first.frame.t_ns) >= span_ns) {
    const std::optional<StereoRelativePose> camera =
        WeightedRelativeStereoPose(first.frame, frame, window_.stereo(), options_.model, options_.init.dynamic_min_landmarks);
    if (camera) {
      rig_search_->AddPair(so3::Log(first.q_gyro.conjugate() * q_gyro), so3::Log(Eigen::Matrix3d(camera->T_a_b.linear())),
                           NanosToSeconds(frame.t_ns - first.frame.t_ns));
    }
  }
  if (!rig_search_->result() && frame.t_ns - rig_search_start_ns_ > SecondsToNanos(kMaxSearchS)) rig_search_->Decide();
  if (rig_search_->result()) {
    ApplyRigRotationSearch(*rig_search_->result());
  } else if (frame.t_ns - rig_search_start_ns_ > SecondsToNanos(kMaxSearchS)) {
    LOG(INFO) << "rig rotation search: too little rotation in the first " << kMaxSearchS
              << " s; sensor.yaml's camera rotation is kept";
    rig_search_.reset();
  }
  if (!rig_search_) rig_frames_.clear();
}

void Estimator::ApplyRigRotationSearch(const RigRotationSearch::Result& result) {
  rig_search_.reset();
  RigRotationSearchReport report;
  report.rotation_vector = result.rotation_vector;
  report.sigma_rad = result.sigma_rad;
  report.pairs = result.pairs;
  report.excited = result.sigma_rad < kMaxRigSearchSigmaRad;
  const double angle = result.rotation_vector.norm();
  const double prior_rad = options_.model.extrinsics_prior_sigma_deg * M_PI / 180.0;
  const Eigen::Vector3d axis = angle > 0 ? Eigen::Vector3d(result.rotation_vector / angle) : Eigen::Vector3d::UnitZ();
  std::ostringstream what;
  what << std::fixed << std::setprecision(2) << "rig rotation search: the gyro follows the camera best with the rig turned by "
       << angle * 180.0 / M_PI << " deg about (" << axis.x() << ", " << axis.y() << ", " << axis.z()
       << ") in the body, +- " << result.sigma_rad * 180.0 / M_PI << " deg (" << result.pairs << " frame pairs, "
       << result.rotation_rad << " rad of camera rotation)";
  if (!report.excited) {
    LOG(INFO) << what.str() << ": the motion did not turn about every axis enough to tell; sensor.yaml's camera "
                               "rotation is kept";
  } else if (angle > std::max(kFarPriorSigmas * prior_rad, kFarSearchSigmas * result.sigma_rad)) {
    report.restart = true;
    LOG(INFO) << what.str() << ": beyond the extrinsics' prior (extrinsics_prior_sigma_deg "
              << options_.model.extrinsics_prior_sigma_deg << ")";
  } else {
    LOG(INFO) << what.str() << ": consistent with sensor.yaml";
  }
  rig_rotation_search_ = report;
}

void Estimator::ApplyTimeOffsetSearch(const TimeOffsetSearch::Result& result) {
  offset_search_.reset();
  const double prior_mean_s = 1e-3 * options_.model.time_offset_prior_mean_ms;
  const double prior_sigma_s = 1e-3 * options_.model.time_offset_prior_sigma_ms;
  const double found_s = prior_mean_s + result.delta_s;
  time_offset_search_ = TimeOffsetSearchReport{found_s, result.sigma_s, result.pairs, false};
  std::ostringstream what;
  what << "time offset search: the gyro follows the camera best at an offset of " << Milliseconds(found_s) << " +- "
       << Milliseconds(result.sigma_s) << " (" << result.pairs << " frame pairs, " << std::setprecision(3)
       << result.rotation_rad << " rad of camera rotation, chi2 " << result.improvement
       << " better than the prior's mean; the prior: " << Milliseconds(prior_mean_s) << " +- "
       << Milliseconds(prior_sigma_s) << ")";
  if (result.at_bound && result.improvement > kBeyondRangeImprovement) {
    what << ", the end of its range (time_offset_search_ms = " << options_.model.time_offset_search_ms
         << "): the camera and IMU clocks are further apart. Set time_offset_prior_mean_ms near the offset (an image "
            "stamped t was taken at IMU time t - offset), or widen time_offset_search_ms";
    input_problem_ = what.str();
  } else if (!result.at_bound && std::abs(result.delta_s) > std::max(kFarPriorSigmas * prior_sigma_s,
                                                                      kFarSearchSigmas * result.sigma_s)) {
    // The windows so far were linearized that far off and their priors keep it: the run is worth
    // starting again with the prior there.
    time_offset_search_->restart = true;
    LOG(INFO) << what.str() << ": beyond the prior";
  } else {
    LOG(INFO) << what.str() << ": consistent with the prior";
  }
}

}  // namespace vio
