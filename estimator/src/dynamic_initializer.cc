#include "vio/estimator/dynamic_initializer.h"

#include <algorithm>
#include <map>
#include <sstream>

#include "vio/estimator/inertial_alignment.h"
#include "vio/estimator/policy.h"
#include "vio/estimator/so3.h"
#include "vio/estimator/stereo_motion.h"
#include "vio/estimator/window_covariance.h"

namespace vio {
namespace {

// Loose priors of the refinement's first state: only the gauge (position,
// yaw) and the accel bias (its zero-mean prior) are real knowledge.
constexpr double kLooseTiltSigma = 0.3;      // [rad]
constexpr double kLooseVelocitySigma = 1.0;  // [m/s]
constexpr double kLooseGyroBiasSigma = 0.1;  // [rad/s]
// The free solve's |g| must be within this fraction of the model's.
constexpr double kMaxGravityNormError = 0.2;
// Noise of each chained stereo position in the linear alignment [m] (the
// refinement then weighs every observation by model.pixel_sigma).
constexpr double kStereoPositionSigma = 0.01;

std::string CheckCoverage(const std::vector<StereoFrame>& frames, const std::vector<ImuSample>& imu) {
  std::ostringstream why;
  if (frames.size() < 3) {
    why << "only " << frames.size() << " frames in the dynamic window";
  } else if (imu.empty() || imu.front().t_ns > frames.front().t_ns || imu.back().t_ns < frames.back().t_ns) {
    why << "the IMU does not cover the frames from t=" << NanosToSeconds(frames.front().t_ns) << " s to t="
        << NanosToSeconds(frames.back().t_ns) << " s";
  }
  return why.str();
}

std::vector<ImuPreintegration> PreintegrateFrames(const std::vector<StereoFrame>& frames,
                                                  const std::vector<ImuSample>& imu, const ImuBias& bias,
                                                  const ImuCalibration& calibration) {
  std::vector<ImuPreintegration> out;
  for (size_t k = 1; k < frames.size(); ++k) {
    out.push_back(PreintegrateBetween(imu, frames[k - 1].t_ns, frames[k].t_ns, bias, calibration));
  }
  return out;
}

// The rotation taking frame 0's body to a z-up world: gravity g_0 onto -z.
Eigen::Quaterniond WorldFromFirst(const Eigen::Vector3d& g_0) {
  return Eigen::Quaterniond::FromTwoVectors(g_0.normalized(), -Eigen::Vector3d::UnitZ());
}

// The prior of the refinement's first state (at its current value).
StatePrior LoosePrior(const Eigen::Quaterniond& q_w_b, const InitOptions& o) {
  StatePrior prior;
  const Eigen::Matrix3d R = q_w_b.toRotationMatrix();
  const Eigen::Vector3d rotation_sigma_w(kLooseTiltSigma, kLooseTiltSigma, o.prior_yaw_sigma);
  prior.pose_covariance.setZero();
  prior.pose_covariance.topLeftCorner<3, 3>() = Eigen::Matrix3d::Identity() * std::pow(o.prior_position_sigma, 2);
  prior.pose_covariance.bottomRightCorner<3, 3>() = R.transpose() * rotation_sigma_w.cwiseAbs2().asDiagonal() * R;
  prior.speed_bias_sigma << Eigen::Vector3d::Constant(kLooseVelocitySigma),
      Eigen::Vector3d::Constant(kLooseGyroBiasSigma), Eigen::Vector3d::Constant(o.prior_accel_bias_sigma);
  return prior;
}

// The window of the refinement: one state per frame at the alignment's
// values, IMU factors between them, the frames' stereo observations.
void BuildRefinementWindow(const std::vector<StereoFrame>& frames, const std::vector<Eigen::Isometry3d>& T_0_k,
                           std::vector<ImuPreintegration> preintegrations, const VelocityGravity& alignment,
                           const Eigen::Vector3d& gyro_bias, const EstimatorOptions& options, Window* window) {
  const Eigen::Quaterniond q_w_0 = WorldFromFirst(alignment.g_0);
  for (size_t k = 0; k < frames.size(); ++k) {
    State& s = window->AddState(StateId(static_cast<std::int64_t>(k)), frames[k].t_ns);
    s.SetPose(q_w_0 * T_0_k[k].translation(), (q_w_0 * Eigen::Quaterniond(T_0_k[k].linear())).normalized());
    // The accel bias prior is zero-mean: the first state gets it at zero, then the aligned value.
    s.SetSpeedBias(q_w_0 * alignment.v_0[k], gyro_bias, k == 0 ? Eigen::Vector3d::Zero() : alignment.accel_bias);
    if (k == 0) {
      window->AddStatePrior(s.id, LoosePrior(s.q_w_b(), options.init));
      s.SetSpeedBias(q_w_0 * alignment.v_0[k], gyro_bias, alignment.accel_bias);
    } else {
      window->AddImuFactor(StateId(static_cast<std::int64_t>(k - 1)), s.id, std::move(preintegrations[k - 1]));
    }
  }
  for (size_t k = 0; k < frames.size(); ++k) {
    AddStereoObservations(frames[k], StateId(static_cast<std::int64_t>(k)), options.model, *window);
  }
}

// Position and yaw of the handed-over state are the new run's gauge: their
// prior is the options' (tight, uncorrelated); tilt, velocity and biases keep
// the refinement's covariance. Over [dp (world), dtheta (body), v, b_g, b_a].
Eigen::Matrix<double, 15, 15> HandOverCovariance(const Eigen::Matrix<double, 15, 15>& covariance,
                                                 const Eigen::Quaterniond& q_w_b, const InitOptions& o) {
  Eigen::Matrix<double, 15, 15> J = Eigen::Matrix<double, 15, 15>::Identity();  // body -> world rotation
  J.block<3, 3>(3, 3) = q_w_b.toRotationMatrix();
  Eigen::Matrix<double, 15, 15> world = J * covariance * J.transpose();
  for (int gauge : {0, 1, 2, 5}) {  // position, yaw
    world.row(gauge).setZero();
    world.col(gauge).setZero();
  }
  world.diagonal().head<3>().setConstant(o.prior_position_sigma * o.prior_position_sigma);
  world(5, 5) = o.prior_yaw_sigma * o.prior_yaw_sigma;
  return J.transpose() * world * J;
}

StatePrior MarginalPrior(const Eigen::Matrix<double, 15, 15>& covariance) {
  StatePrior prior;
  prior.pose_covariance = covariance.topLeftCorner<6, 6>();
  prior.speed_bias_sigma = covariance.diagonal().tail<9>().cwiseSqrt();
  return prior;
}

// Roll/pitch standard deviation (the larger) and speed standard deviation (largest axis) of a
// state covariance.
std::pair<double, double> TiltAndVelocitySigma(const Eigen::Matrix<double, 15, 15>& covariance,
                                               const Eigen::Quaterniond& q_w_b) {
  const Eigen::Matrix3d R = q_w_b.toRotationMatrix();
  const Eigen::Matrix3d rotation_w = R * covariance.block<3, 3>(3, 3) * R.transpose();
  const double tilt = std::sqrt(std::max(rotation_w(0, 0), rotation_w(1, 1)));
  return {tilt, std::sqrt(covariance.diagonal().segment<3>(6).maxCoeff())};
}

// The newest state of the refined window, or why it is not determined enough.
DynamicInitResult FromRefinedWindow(Window& window, const InitOptions& o) {
  DynamicInitResult result;
  const std::optional<StateCovariance> covariance = NewestStateCovariance(window);
  const State& newest = window.states().rbegin()->second;
  std::ostringstream why;
  if (!covariance) {
    result.reason = "the refinement's information is singular: the motion does not determine the state";
    return result;
  }
  const auto [tilt_sigma, velocity_sigma] = TiltAndVelocitySigma(covariance->covariance, newest.q_w_b());
  if (tilt_sigma > o.dynamic_max_tilt_sigma || velocity_sigma > o.dynamic_max_velocity_sigma) {
    why << "gravity direction or velocity not determined yet (roll/pitch sigma " << tilt_sigma << " rad, limit "
        << o.dynamic_max_tilt_sigma << "; velocity sigma " << velocity_sigma << " m/s, limit "
        << o.dynamic_max_velocity_sigma << ")";
    result.reason = why.str();
    return result;
  }
  for (const auto& [id, s] : window.states()) {
    InitialState state;
    state.t_ns = s.t_ns;
    state.p_w_b = s.p_w_b();
    state.q_w_b = s.q_w_b();
    state.v_w_b = s.v_w_b();
    state.gyro_bias = s.gyro_bias();
    state.accel_bias = s.accel_bias();
    if (id == newest.id) {
      result.state = state;
    } else {
      result.earlier.push_back(state);
    }
  }
  const InitialState& state = *result.state;
  result.covariance = covariance->covariance;
  result.prior_covariance = HandOverCovariance(covariance->covariance, state.q_w_b, o);
  result.prior = MarginalPrior(result.prior_covariance);
  return result;
}

}  // namespace

DynamicInitResult InitializeDynamic(const std::vector<StereoFrame>& frames, const std::vector<ImuSample>& imu,
                                    const ImuCalibration& calibration, const RectifiedStereo& stereo,
                                    const EstimatorOptions& options) {
  DynamicInitResult result;
  result.reason = CheckCoverage(frames, imu);
  if (!result.reason.empty()) return result;
  const StereoTrajectory motion = ChainStereoPoses(frames, stereo, options.model, options.init.dynamic_min_landmarks);
  if (!motion.failure.empty()) {
    result.reason = motion.failure;
    return result;
  }
  std::vector<ImuPreintegration> preintegrations = PreintegrateFrames(frames, imu, ImuBias{}, calibration);
  ImuBias bias;
  for (int iteration = 0; iteration < 2; ++iteration) {
    bias.gyro = AlignGyroBias(motion.T_0_k, preintegrations);
    preintegrations = PreintegrateFrames(frames, imu, bias, calibration);
  }
  const VelocityGravity alignment = AlignVelocityGravity(motion.T_0_k, preintegrations, options.model.gravity,
                                                         options.init.prior_accel_bias_sigma, kStereoPositionSigma);
  result.free_gravity_norm = alignment.free_gravity_norm;
  if (std::abs(alignment.free_gravity_norm - options.model.gravity) > kMaxGravityNormError * options.model.gravity) {
    std::ostringstream why;
    why << "stereo motion and IMU disagree: the alignment's gravity is " << alignment.free_gravity_norm
        << " m/s^2 (model " << options.model.gravity << ")";
    result.reason = why.str();
    return result;
  }
  Window window(options.model, stereo);
  BuildRefinementWindow(frames, motion.T_0_k, std::move(preintegrations), alignment, bias.gyro, options, &window);
  window.RefreshImuFactors(options.model.reintegrate_bias_threshold);
  const SolveReport report = window.Solve(options.solver);
  if (!report.usable) {
    result.reason = "the refinement's bundle adjustment did not give a usable solution";
    return result;
  }
  DynamicInitResult refined = FromRefinedWindow(window, options.init);
  refined.free_gravity_norm = alignment.free_gravity_norm;
  return refined;
}

std::optional<double> CameraPixelMotion(const std::vector<StereoFrame>& frames, int min_landmarks) {
  if (frames.empty()) return std::nullopt;
  std::map<LandmarkId, Eigen::Vector2d> first;
  for (const StereoObservation& obs : frames.front().observations) first[obs.landmark] = {obs.z_px.x(), obs.z_px.z()};
  std::optional<double> largest;
  for (size_t k = 1; k < frames.size(); ++k) {
    std::vector<double> moved;
    for (const StereoObservation& obs : frames[k].observations) {
      const auto it = first.find(obs.landmark);
      if (it != first.end()) moved.push_back((Eigen::Vector2d(obs.z_px.x(), obs.z_px.z()) - it->second).norm());
    }
    if (static_cast<int>(moved.size()) < min_landmarks) continue;
    std::nth_element(moved.begin(), moved.begin() + moved.size() / 2, moved.end());
    largest = std::max(largest.value_or(0.0), moved[moved.size() / 2]);
  }
  return largest;
}

}  // namespace vio
