#include "vio/estimator/estimator.h"

#include <algorithm>
#include <chrono>
#include <iomanip>
#include <map>
#include <sstream>

#include <glog/logging.h>

#include "vio/estimator/dynamic_initializer.h"
#include "vio/estimator/so3.h"
#include "vio/estimator/stereo_geometry.h"
#include "vio/estimator/stereo_motion.h"

namespace vio {
namespace {

// Batch keeps every state and landmark: its window removes only re-preintegrated IMU factors. The
// MSCKF without a local map holds one frame's tracks: a removal's scan of its few hundred residuals
// costs less than a hash-set node per residual and parameter block.
ResidualIndex ResidualIndexFor(const EstimatorOptions& options) {
  const bool one_frames_tracks = options.policy.policy == "msckf" && options.local_map.local_map_keyframes == 0;
  return options.policy.policy == "batch" || one_frames_tracks ? ResidualIndex::kNone : ResidualIndex::kPerBlock;
}

}  // namespace

Estimator::Estimator(const EstimatorOptions& options, const ImuCalibration& imu, const RectifiedStereo& stereo)
    : options_(options),
      imu_calibration_(imu),
      window_(options.model, stereo, ResidualIndexFor(options)),
      policy_(MakePolicy(options)),
      tracking_(options.policy.min_frame_features, options.policy.window_size),
      rig_limits_(RigLimitsFor(imu, options.model.gravity)) {
  imu_calibration_.gyro_noise_density *= options.model.imu_noise_scale;
  imu_calibration_.accel_noise_density *= options.model.imu_noise_scale;
  imu_calibration_.gyro_random_walk *= options.model.imu_noise_scale;
  imu_calibration_.accel_random_walk *= options.model.imu_noise_scale;
  EstimateCalibration();
  if (options_.model.extrinsics_rotation_search) rig_search_.emplace();
}

void Estimator::EstimateCalibration() {
  const ModelOptions& model = options_.model;
  if ((model.estimate_time_offset || model.estimate_extrinsics) && options_.local_map.local_map_keyframes > 0) {
    // Parked keyframes leave the cost with their priors (Window::RemoveState): not measured with
    // the calibration in those priors, so the local map keeps the sensor.yaml rig and the prior mean as exact.
    LOG(WARNING) << "estimate_time_offset and estimate_extrinsics are not available with local_map_keyframes > 0: "
                    "the time offset is taken as time_offset_prior_mean_ms and the extrinsics as given";
    return;
  }
  if (model.estimate_time_offset) {
    window_.EstimateTimeOffset(1e-3 * model.time_offset_prior_mean_ms, 1e-3 * model.time_offset_prior_sigma_ms);
    StartTimeOffsetSearch();
  }
  if (model.estimate_extrinsics) {
    window_.EstimateExtrinsics(model.extrinsics_prior_sigma_deg * M_PI / 180.0, model.extrinsics_prior_sigma_m);
  }
}

double Estimator::time_offset_s() const {
  return window_.estimates_time_offset() ? window_.time_offset_s() : 1e-3 * options_.model.time_offset_prior_mean_ms;
}

Timestamp Estimator::AppliedTimeOffsetNs() const { return SecondsToNanos(time_offset_s()); }

CameraMotion Estimator::NewestCameraMotion() const {
  const State& s = window_.state(last_state_);
  // The bias-corrected gyro at the frame: the IMU sample nearest its time.
  const auto after = std::lower_bound(imu_.begin(), imu_.end(), s.t_ns,
                                      [](const ImuSample& m, Timestamp t) { return m.t_ns < t; });
  if (imu_.empty()) return CameraMotion{};
  auto nearest = after == imu_.end() ? std::prev(after) : after;
  if (nearest != imu_.begin() && s.t_ns - std::prev(nearest)->t_ns < nearest->t_ns - s.t_ns) nearest = std::prev(nearest);
  return CameraMotionOf(window_.estimated_stereo(), s.q_w_b(), s.v_w_b(), nearest->gyro_rad_s - s.gyro_bias());
}

void Estimator::AddImu(const ImuSample& sample) {
  CHECK(imu_.empty() || sample.t_ns > imu_.back().t_ns) << "IMU samples out of order at " << sample.t_ns;
  imu_.push_back(sample);
  if (offset_search_) offset_search_->AddGyro(sample.t_ns, sample.gyro_rad_s);
}

void Estimator::SetInitialState(const InitialState& state) { given_initial_state_ = state; }

FrameEstimate Estimator::ProcessFrame(const StereoFrame& camera_frame) {
  const auto start = std::chrono::steady_clock::now();
  window_.ClearRemovals();
  FrameTiming timing;
  // The frame at the IMU time it was taken (the offset's current estimate), after the last state.
  StereoFrame frame = camera_frame;
  frame.t_ns = ImuTimeOf(camera_frame.t_ns);
  if (window_.estimates_time_offset()) {  // within the IMU given so far, after the last state
    if (!imu_.empty()) frame.t_ns = std::min(frame.t_ns, imu_.back().t_ns);
    if (last_state_.valid()) frame.t_ns = std::max(frame.t_ns, window_.state(last_state_).t_ns + 1'000'000);
  }
  const double applied_offset_s = NanosToSeconds(camera_frame.t_ns - frame.t_ns);
  CheckRotation(frame, camera_frame.t_ns - SecondsToNanos(1e-3 * options_.model.time_offset_prior_mean_ms));
  if (!last_state_.valid()) {
    if (!Initialize(frame)) {
      FrameEstimate waiting;
      waiting.t_ns = frame.t_ns;
      return waiting;
    }
  } else {
    AddPropagatedState(frame.t_ns);
  }
  if (window_.estimates_time_offset()) {
    const CameraMotion motion = NewestCameraMotion();
    if (log_) {
      if (!log_->time_offset) {
        log_->time_offset = LoggedTimeOffset{1e-3 * options_.model.time_offset_prior_mean_ms,
                                             1e-3 * options_.model.time_offset_prior_sigma_ms, 0.0};
      }
      log_->states.back().applied_offset_s = applied_offset_s;
      log_->states.back().camera_motion = motion;
    }
    window_.SetCameraTiming(last_state_, applied_offset_s, motion);
  }
  timing.propagate_ms = MillisecondsSince(start);
  const bool tracked = tracking_.Observe(frame.t_ns, static_cast<int>(frame.observations.size()));
  const StereoFrame used = tracked ? GateObservations(frame) : StereoFrame{frame.t_ns, {}};
  if (log_) log_->states.back().observations = used.observations;
  timing.policy = policy_->Update(used, last_state_, window_);
  if (log_ && log_->time_offset) log_->time_offset->estimate_s = window_.time_offset_s();
  PruneImu(window_.states().begin()->second.t_ns);
  for (const State& s : window_.removals().leaving_states) left_window_.push_back(EstimateOf(s));
  if (log_) {
    for (const auto& [id, p_w] : window_.removals().leaving_landmarks) log_->landmarks[id] = p_w;
  }
  FrameEstimate estimate = Estimate(frame);
  timing.total_ms = MillisecondsSince(start);
  estimate.timing = timing;
  return estimate;
}

bool Estimator::Initialize(const StereoFrame& frame) {
  if (given_initial_state_) {
    InitialState initial = *given_initial_state_;
    initial.t_ns = frame.t_ns;
    AddFirstState(initial, DefaultFirstPrior(initial.q_w_b));
    init_method_ = "groundtruth";
    return true;
  }
  const InitOptions& o = options_.init;
  const double kept_s = std::max(o.static_window_s, o.dynamic_window_s) + 0.1;
  init_frames_.erase(std::remove_if(init_frames_.begin(), init_frames_.end(),
                                    [&](const StereoFrame& f) { return f.t_ns < frame.t_ns - SecondsToNanos(kept_s); }),
                     init_frames_.end());
  init_frames_.push_back(frame);
  std::string static_reason, dynamic_reason;
  bool moving = o.init == "dynamic";
  if (o.init != "dynamic") {
    if (const std::optional<InitialState> state = TryStatic(frame, &static_reason, &moving)) {
      AddFirstState(*state, DefaultFirstPrior(state->q_w_b));
      init_method_ = "static";
      for (const StereoFrame& f : InitFrames(frame.t_ns, o.static_window_s)) {
        if (f.t_ns == frame.t_ns) continue;
        InitialState at_rest = *state;
        at_rest.t_ns = f.t_ns;
        earlier_estimates_.push_back(EstimateOfInitial(at_rest));
        left_window_.push_back(earlier_estimates_.back());
      }
      init_frames_.clear();
      return true;
    }
  }
  if (moving && o.init != "static" && TryDynamic(&dynamic_reason)) return true;
  const std::string reason = o.init == "static"    ? static_reason
                             : o.init == "dynamic" ? dynamic_reason
                             : !moving             ? "static: " + static_reason
                                                   : "static: " + static_reason + "; dynamic: " + dynamic_reason;
  if (moving && !waiting_while_moving_) LOG(WARNING) << "waiting for initialization: " << reason;
  waiting_while_moving_ = moving;
  waiting_reason_ = reason;
  return false;
}

std::optional<InitialState> Estimator::TryStatic(const StereoFrame& frame, std::string* reason, bool* moving) {
  const StaticInitResult result = InitializeStatic(imu_, frame.t_ns, options_.init);
  *moving = result.moving;
  *reason = result.reason;
  if (!result.state || options_.init.init != "auto") return result.state;
  // The IMU can be still while the rig glides at constant velocity: the camera decides.
  const std::optional<double> moved = CameraPixelMotion(InitFrames(frame.t_ns, options_.init.static_window_s),
                                                        options_.init.dynamic_min_landmarks);
  if (moved && *moved > options_.init.static_max_camera_motion_px) {
    std::ostringstream why;
    why << "the IMU is still but the image moved " << *moved << " px (median over the landmarks) in the last "
        << options_.init.static_window_s << " s (limit static_max_camera_motion_px = "
        << options_.init.static_max_camera_motion_px << ")";
    *reason = why.str();
    *moving = true;
    LOG(INFO) << "no static initialization: " << *reason;
    return std::nullopt;
  }
  if (const std::string problem = CheckAtRest(result.accel_mean, result.state->gyro_bias, rig_limits_);
      !problem.empty()) {
    *reason = problem;
    input_problem_ = problem;
    return std::nullopt;
  }
  LOG(INFO) << "static initialization at t=" << std::fixed << std::setprecision(3) << NanosToSeconds(frame.t_ns)
            << " s";
  return result.state;
}

bool Estimator::TryDynamic(std::string* reason) {
  const InitOptions& o = options_.init;
  const std::vector<StereoFrame> frames = InitFrames(init_frames_.back().t_ns, o.dynamic_window_s);
  const double span_s = NanosToSeconds(frames.back().t_ns - frames.front().t_ns);
  if (span_s < 0.9 * o.dynamic_window_s - 1e-3) {  // 10 % short (a dropped frame), and round-off
    std::ostringstream why;
    why << "collecting frames (" << span_s << " of " << o.dynamic_window_s << " s)";
    *reason = why.str();
    return false;
  }
  const DynamicInitResult result = InitializeDynamic(frames, imu_, imu_calibration_, window_.stereo(), options_);
  if (const std::string implausible = CheckDynamicResult(result); !implausible.empty()) {
    *reason = implausible;
    return false;
  }
  if (!result.state) {
    *reason = result.reason;
    return false;
  }
  LOG(INFO) << "dynamic initialization at t=" << std::fixed << std::setprecision(3)
            << NanosToSeconds(result.state->t_ns) << " s from " << frames.size() << " frames (" << span_s
            << " s): |v| " << result.state->v_w_b.norm() << " m/s, gyro bias " << result.state->gyro_bias.transpose()
            << " rad/s, accel bias " << result.state->accel_bias.transpose() << " m/s^2; sigmas (v, b_g, b_a) "
            << result.prior.speed_bias_sigma.transpose();
  AddFirstState(*result.state, result.prior_covariance);
  init_method_ = "dynamic";
  for (const InitialState& earlier : result.earlier) {
    earlier_estimates_.push_back(EstimateOfInitial(earlier));
    left_window_.push_back(earlier_estimates_.back());
  }
  init_frames_.clear();
  return true;
}

std::vector<StereoFrame> Estimator::InitFrames(Timestamp t_ns, double span_s) const {
  std::vector<StereoFrame> frames;
  for (const StereoFrame& f : init_frames_) {
    if (f.t_ns >= t_ns - SecondsToNanos(span_s) && f.t_ns <= t_ns) frames.push_back(f);
  }
  return frames;
}

StatePrior Estimator::DefaultFirstPrior(const Eigen::Quaterniond& q_w_b) const {
  const InitOptions& o = options_.init;
  StatePrior prior;
  // Roll/pitch and yaw are world-frame angles; the tangent's rotation is in
  // the body frame: Sigma_body = R_w_b^T Sigma_world R_w_b.
  const Eigen::Matrix3d R_w_b = q_w_b.toRotationMatrix();
  const Eigen::Vector3d rotation_sigma_w(o.prior_tilt_sigma, o.prior_tilt_sigma, o.prior_yaw_sigma);
  prior.pose_covariance.setZero();
  prior.pose_covariance.topLeftCorner<3, 3>() =
      Eigen::Matrix3d::Identity() * (o.prior_position_sigma * o.prior_position_sigma);
  prior.pose_covariance.bottomRightCorner<3, 3>() =
      R_w_b.transpose() * rotation_sigma_w.cwiseAbs2().asDiagonal() * R_w_b;
  prior.speed_bias_sigma << Eigen::Vector3d::Constant(o.prior_velocity_sigma),
      Eigen::Vector3d::Constant(o.prior_gyro_bias_sigma), Eigen::Vector3d::Constant(o.prior_accel_bias_sigma);
  return prior;
}

void Estimator::AddFirstState(const InitialState& initial, const Eigen::Matrix<double, 15, 15>& covariance) {
  last_state_ = StateId(next_state_id_++);
  State& s = window_.AddState(last_state_, initial.t_ns);
  s.SetPose(initial.p_w_b, initial.q_w_b);
  s.SetSpeedBias(initial.v_w_b, initial.gyro_bias, initial.accel_bias);
  // A Gaussian prior N(x0, covariance) as a linear factor: jacobian = covariance^-1/2, residual 0.
  const Eigen::Matrix<double, 15, 15> information = covariance.inverse();
  const Eigen::LLT<Eigen::Matrix<double, 15, 15>> llt(0.5 * (information + information.transpose()));
  CHECK(llt.info() == Eigen::Success) << "the dynamic initializer's covariance is not positive definite";
  window_.AddLinearFactor({last_state_}, {}, llt.matrixU().toDenseMatrix(), Eigen::VectorXd::Zero(15));
  waiting_reason_.clear();
  if (log_) {
    log_->first_covariance = covariance;
    log_->states.push_back({last_state_, initial.t_ns, {}, std::nullopt});
  }
}

void Estimator::AddFirstState(const InitialState& initial, const StatePrior& prior) {
  last_state_ = StateId(next_state_id_++);
  State& s = window_.AddState(last_state_, initial.t_ns);
  s.SetPose(initial.p_w_b, initial.q_w_b);
  s.SetSpeedBias(initial.v_w_b, initial.gyro_bias, initial.accel_bias);
  window_.AddStatePrior(last_state_, prior);
  waiting_reason_.clear();
  if (log_) {
    log_->first_prior = prior;
    log_->states.push_back({last_state_, initial.t_ns, {}, std::nullopt});
  }
}

// The state at t_ns predicted from the last one through the preintegrated
// IMU (Forster et al. eq. 33), with the preintegration that links them.
Estimator::Prediction Estimator::Predict(Timestamp t_ns) const {
  const State& last = window_.state(last_state_);
  Prediction out{PreintegrateBetween(imu_, last.t_ns, t_ns, ImuBias{last.gyro_bias(), last.accel_bias()},
                                     imu_calibration_)};
  const ImuPreintegration::Deltas& d = out.preintegration.deltas();
  const Eigen::Vector3d g_w(0, 0, -options_.model.gravity);
  const double dt = NanosToSeconds(t_ns - last.t_ns);
  const Eigen::Matrix3d R_w_i = last.q_w_b().toRotationMatrix();
  out.p_w_b = last.p_w_b() + last.v_w_b() * dt + 0.5 * g_w * dt * dt + R_w_i * d.delta_p;
  out.v_w_b = last.v_w_b() + g_w * dt + R_w_i * d.delta_v;
  out.q_w_b = (last.q_w_b() * d.delta_q).normalized();
  return out;
}

std::optional<Eigen::Isometry3d> Estimator::PredictBodyPose(Timestamp t_ns) const {
  if (!last_state_.valid() || imu_.empty() || imu_.back().t_ns < t_ns) return std::nullopt;
  const Prediction p = Predict(t_ns);
  Eigen::Isometry3d T_w_b = Eigen::Isometry3d::Identity();
  T_w_b.linear() = p.q_w_b.toRotationMatrix();
  T_w_b.translation() = p.p_w_b;
  return T_w_b;
}

// Adds the predicted state and links it to the last one by an IMU factor.
void Estimator::AddPropagatedState(Timestamp t_ns) {
  Prediction p = Predict(t_ns);
  const State& last = window_.state(last_state_);
  const Eigen::Vector3d b_g = last.gyro_bias(), b_a = last.accel_bias();
  const StateId previous = last_state_;
  last_state_ = StateId(next_state_id_++);
  State& s = window_.AddState(last_state_, t_ns);
  s.SetPose(p.p_w_b, p.q_w_b);
  s.SetSpeedBias(p.v_w_b, b_g, b_a);
  if (log_) log_->states.push_back({last_state_, t_ns, {}, p.preintegration});
  window_.AddImuFactor(previous, last_state_, std::move(p.preintegration));
}

std::vector<FrameEstimate> Estimator::Finish() {
  std::vector<FrameEstimate> smoothed;
  if (!last_state_.valid() || !policy_->Finish(window_)) return smoothed;
  for (const auto& [id, s] : window_.states()) smoothed.push_back(EstimateOf(s));
  return smoothed;
}

std::vector<FrameEstimate> Estimator::LastEstimates() const {
  std::vector<FrameEstimate> last = left_window_;
  for (const State& s : policy_->StatesBehindWindow(window_)) last.push_back(EstimateOf(s));
  for (const auto& [id, s] : window_.states()) last.push_back(EstimateOf(s));
  return last;
}

std::vector<FrameEstimate> Estimator::Refine(RefinementReport* report) const {
  std::vector<FrameEstimate> refined;
  if (!log_ || log_->states.empty()) return refined;
  std::map<Timestamp, FrameEstimate> last;
  for (const FrameEstimate& e : LastEstimates()) last[e.t_ns] = e;
  const StartValue start = [&last](const LoggedState& logged, State* s) {
    const auto it = last.find(logged.t_ns);
    if (it == last.end()) return false;
    s->SetPose(it->second.p_w_b, it->second.q_w_b);
    s->SetSpeedBias(it->second.v_w_b, it->second.gyro_bias, it->second.accel_bias);
    return true;
  };
  LandmarkStarts landmarks = log_->landmarks;
  for (const auto& [id, landmark] : window_.landmarks()) landmarks[id] = landmark.position();
  // Every state and landmark of the run, nothing removed but the observations that do not evaluate at the start.
  Window whole(options_.model, window_.estimated_stereo(), ResidualIndex::kNone);
  whole.SetSolveControl(window_.solve_control());
  *report = vio::Refine(*log_, start, landmarks, options_, whole);
  if (!report->usable) return refined;
  for (const auto& [id, s] : whole.states()) refined.push_back(EstimateOf(s));
  return refined;
}

FrameEstimate Estimator::EstimateOfInitial(const InitialState& s) {
  FrameEstimate e;
  e.t_ns = s.t_ns;
  e.initialized = true;
  e.p_w_b = s.p_w_b;
  e.q_w_b = s.q_w_b;
  e.v_w_b = s.v_w_b;
  e.gyro_bias = s.gyro_bias;
  e.accel_bias = s.accel_bias;
  return e;
}

FrameEstimate Estimator::EstimateOf(const State& s) const {
  FrameEstimate e;
  e.t_ns = s.t_ns;
  e.initialized = true;
  e.p_w_b = s.p_w_b();
  e.q_w_b = s.q_w_b();
  e.v_w_b = s.v_w_b();
  e.gyro_bias = s.gyro_bias();
  e.accel_bias = s.accel_bias();
  return e;
}

// An observation of a landmark already in the window whose whitened
// reprojection error at the new (IMU-predicted) state is beyond the gate is
// an outlier: it never reaches the cost.
StereoFrame Estimator::GateObservations(const StereoFrame& frame) {
  StereoFrame kept = frame;
  kept.observations.clear();
  for (const StereoObservation& obs : frame.observations) {
    if (window_.HasLandmark(obs.landmark) &&
        !(window_.WhitenedError(last_state_, obs.landmark, obs.z_px) <= options_.model.max_whitened_residual)) {
      ++rejected_observations_;
      continue;
    }
    kept.observations.push_back(obs);
  }
  return kept;
}

FrameEstimate Estimator::Estimate(const StereoFrame& frame) const {
  FrameEstimate e = EstimateOf(window_.state(last_state_));
  e.t_ns = frame.t_ns;
  e.num_states = static_cast<int>(window_.states().size());
  e.num_landmarks = static_cast<int>(window_.landmarks().size());
  e.num_observations = static_cast<int>(frame.observations.size());
  e.num_residuals = window_.num_residual_blocks();
  return e;
}

// Keeps the IMU samples the window may still need (re-preintegration uses the
// factor's own copy) plus one before, for interpolation at the boundary.
void Estimator::PruneImu(Timestamp before_ns) {
  auto it = std::lower_bound(imu_.begin(), imu_.end(), before_ns,
                             [](const ImuSample& m, Timestamp t) { return m.t_ns < t; });
  if (it != imu_.begin()) --it;
  imu_.erase(imu_.begin(), it);
}

}  // namespace vio
