#include "vio/simulator/trajectory.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

namespace vio::tools {
namespace {

/// amplitude * sin(frequency * u + phase)
struct Harmonic {
  double amplitude;
  int frequency;
  double phase;
};

/// Value and first two derivatives (d/du) of a sum of harmonics.
struct Series {
  double value = 0.0, d_u = 0.0, d_uu = 0.0;
};

template <std::size_t N>
Series EvaluateSeries(const std::array<Harmonic, N>& harmonics, double u) {
  Series out;
  for (const Harmonic& h : harmonics) {
    const double arg = h.frequency * u + h.phase;
    out.value += h.amplitude * std::sin(arg);
    out.d_u += h.amplitude * h.frequency * std::cos(arg);
    out.d_uu -= h.amplitude * h.frequency * h.frequency * std::sin(arg);
  }
  return out;
}

// Normalized shapes: |x|, |y|, |z| <= 1 (amplitudes sum to 1).
constexpr std::array<Harmonic, 2> kShapeX = {{{0.75, 1, 0.0}, {0.25, 3, 0.5}}};
constexpr std::array<Harmonic, 2> kShapeY = {{{0.70, 2, 0.3}, {0.30, 1, 1.1}}};
constexpr std::array<Harmonic, 2> kShapeZ = {{{0.60, 3, 0.7}, {0.40, 1, 2.0}}};
// Yaw = u + this (one full turn per loop, swinging back and forth).
constexpr std::array<Harmonic, 1> kYawSwing = {{{0.6, 2, 0.4}}};
// Pitch and roll, scaled by the tilt amplitude.
constexpr std::array<Harmonic, 1> kPitch = {{{1.0, 3, 1.3}}};
constexpr std::array<Harmonic, 1> kRoll = {{{1.0, 5, 0.2}}};

// septic smoothstep h(x), its integral H(x) and derivative h'(x) on [0, 1]
double SmoothStep(double x) { return x * x * x * x * (35.0 + x * (-84.0 + x * (70.0 - 20.0 * x))); }
double SmoothStepIntegral(double x) {
  return x * x * x * x * x * (7.0 + x * (-14.0 + x * (10.0 - 2.5 * x)));
}
double SmoothStepDerivative(double x) {
  return x * x * x * (140.0 + x * (-420.0 + x * (420.0 - 140.0 * x)));
}

struct Attitude {  // yaw, pitch, roll and their u-derivatives
  Series yaw, pitch, roll;
};

Attitude EvaluateAttitude(double u, double tilt_rad) {
  Attitude att;
  att.yaw = EvaluateSeries(kYawSwing, u);
  att.yaw.value += u;
  att.yaw.d_u += 1.0;
  att.pitch = EvaluateSeries(kPitch, u);
  att.roll = EvaluateSeries(kRoll, u);
  for (Series* s : {&att.pitch, &att.roll}) {
    s->value *= tilt_rad;
    s->d_u *= tilt_rad;
    s->d_uu *= tilt_rad;
  }
  return att;
}

Eigen::Matrix3d HeadingRotation(const Attitude& att) {
  return (Eigen::AngleAxisd(att.yaw.value, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(att.pitch.value, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(att.roll.value, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

// World angular velocity per unit of u of R = Rz(yaw) Ry(pitch) Rx(roll):
//   omega_w = yaw_u e_z + pitch_u Rz e_y + roll_u Rz Ry e_x
Eigen::Vector3d AngularVelocityPerU(const Attitude& att) {
  const Eigen::Matrix3d Rz = Eigen::AngleAxisd(att.yaw.value, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Matrix3d Ry = Eigen::AngleAxisd(att.pitch.value, Eigen::Vector3d::UnitY()).toRotationMatrix();
  return att.yaw.d_u * Eigen::Vector3d::UnitZ() + att.pitch.d_u * (Rz * Eigen::Vector3d::UnitY()) +
         att.roll.d_u * (Rz * Ry * Eigen::Vector3d::UnitX());
}

Eigen::Vector3d PositionShapeDerivative(double u, const Eigen::Vector3d& half_extent) {
  return Eigen::Vector3d(EvaluateSeries(kShapeX, u).d_u, EvaluateSeries(kShapeY, u).d_u, EvaluateSeries(kShapeZ, u).d_u)
      .cwiseProduct(half_extent);
}

void CheckOptions(const SyntheticTrajectoryOptions& options) {
  if (!(options.half_extent_m.minCoeff() >= 0.0) || !(options.max_speed_m_s > 0.0) ||
      !(options.max_rotation_rate_rad_s > 0.0) || !(options.ramp_duration_s > 0.0) ||
      !(options.static_duration_s >= 0.0) || !(options.start_offset_s >= 0.0)) {
    throw std::invalid_argument(
        "synthetic trajectory: need extents >= 0, max speed > 0, max rotation rate > 0, ramp > 0 "
        "and static duration and start offset >= 0");
  }
}

}  // namespace

Eigen::Matrix3d HeadingFromBody() {
  Eigen::Matrix3d R_r_b;
  // columns: body x, y, z in the heading frame (x forward, y left, z up)
  R_r_b << 0.0, 0.0, 1.0,  //
      0.0, -1.0, 0.0,      //
      1.0, 0.0, 0.0;
  return R_r_b;
}

SyntheticTrajectory::SyntheticTrajectory(const SyntheticTrajectoryOptions& options) : options_(options) {
  CheckOptions(options);
  constexpr int kSamples = 8192;
  double max_speed_per_u = 0.0, max_rate_per_u = 0.0;
  for (int i = 0; i < kSamples; ++i) {
    const double u = 2.0 * M_PI * i / kSamples;
    max_speed_per_u = std::max(max_speed_per_u, PositionShapeDerivative(u, options.half_extent_m).norm());
    max_rate_per_u = std::max(max_rate_per_u,
                              AngularVelocityPerU(EvaluateAttitude(u, options.tilt_amplitude_rad)).norm());
  }
  // |v| = |df/du| * 2 pi / P, |omega| = |omega_u| * 2 pi / P; 1 % margin for sampling.
  period_s_ = 1.01 * 2.0 * M_PI *
              std::max(max_speed_per_u / options.max_speed_m_s, max_rate_per_u / options.max_rotation_rate_rad_s);
}

SyntheticTrajectory::Phase SyntheticTrajectory::WarpTime(double t_s) const {
  const double k = 2.0 * M_PI / period_s_;
  const double tau = t_s + options_.start_offset_s - options_.static_duration_s;
  const double ramp = options_.ramp_duration_s;
  Phase phase;
  if (tau <= 0.0) return phase;
  if (tau < ramp) {
    const double x = tau / ramp;
    phase.u = k * ramp * SmoothStepIntegral(x);
    phase.u_dot = k * SmoothStep(x);
    phase.u_ddot = k * SmoothStepDerivative(x) / ramp;
    return phase;
  }
  phase.u = k * (0.5 * ramp + (tau - ramp));
  phase.u_dot = k;
  return phase;
}

KinematicState SyntheticTrajectory::Evaluate(double t_s) const {
  const Phase phase = WarpTime(t_s);
  const Eigen::Vector3d& A = options_.half_extent_m;
  const Series x = EvaluateSeries(kShapeX, phase.u);
  const Series y = EvaluateSeries(kShapeY, phase.u);
  const Series z = EvaluateSeries(kShapeZ, phase.u);
  const Eigen::Vector3d f(x.value, y.value, z.value), f_u(x.d_u, y.d_u, z.d_u),
      f_uu(x.d_uu, y.d_uu, z.d_uu);
  KinematicState state;
  state.p_w_b = options_.center_w + A.cwiseProduct(f);
  state.v_w_b = A.cwiseProduct(f_u) * phase.u_dot;
  state.a_w_b = A.cwiseProduct(f_uu * phase.u_dot * phase.u_dot + f_u * phase.u_ddot);
  const Attitude att = EvaluateAttitude(phase.u, options_.tilt_amplitude_rad);
  const Eigen::Matrix3d R_w_b = HeadingRotation(att) * HeadingFromBody();
  state.q_w_b = Eigen::Quaterniond(R_w_b).normalized();
  state.omega_b = R_w_b.transpose() * AngularVelocityPerU(att) * phase.u_dot;
  return state;
}

std::optional<Eigen::Isometry3d> InterpolatePose(const std::vector<GroundTruthState>& groundtruth,
                                                 Timestamp t_ns) {
  if (groundtruth.empty() || t_ns < groundtruth.front().t_ns || t_ns > groundtruth.back().t_ns) {
    return std::nullopt;
  }
  const auto after = std::lower_bound(groundtruth.begin(), groundtruth.end(), t_ns,
                                      [](const GroundTruthState& s, Timestamp t) { return s.t_ns < t; });
  const GroundTruthState& b = *after;
  const GroundTruthState& a = after == groundtruth.begin() ? b : *(after - 1);
  const double alpha = b.t_ns == a.t_ns ? 0.0 : NanosToSeconds(t_ns - a.t_ns) / NanosToSeconds(b.t_ns - a.t_ns);
  Eigen::Isometry3d T_w_b = Eigen::Isometry3d::Identity();
  T_w_b.linear() = a.q_w_b.normalized().slerp(alpha, b.q_w_b.normalized()).toRotationMatrix();
  T_w_b.translation() = (1.0 - alpha) * a.p_w_b + alpha * b.p_w_b;
  return T_w_b;
}

std::vector<GroundTruthJump> FindGroundTruthJumps(const std::vector<GroundTruthState>& groundtruth,
                                                  double tolerance_m_s) {
  std::vector<GroundTruthJump> jumps;
  for (size_t i = 1; i < groundtruth.size(); ++i) {
    const GroundTruthState& a = groundtruth[i - 1];
    const GroundTruthState& b = groundtruth[i];
    if (!a.has_velocity_and_biases || b.t_ns <= a.t_ns) continue;
    const double dt_s = NanosToSeconds(b.t_ns - a.t_ns);
    const Eigen::Vector3d step = b.p_w_b - a.p_w_b;
    const Eigen::Vector3d mean_velocity = 0.5 * (a.v_w_b + b.v_w_b);
    if ((step / dt_s - mean_velocity).norm() <= tolerance_m_s) continue;
    jumps.push_back({a.t_ns, b.t_ns, step.norm(), step.norm() / dt_s, mean_velocity.norm(), step - dt_s * mean_velocity});
  }
  return jumps;
}

std::vector<GroundTruthState> RemoveGroundTruthJumps(std::vector<GroundTruthState> groundtruth,
                                                     const std::vector<GroundTruthJump>& jumps) {
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
  auto jump = jumps.begin();
  for (GroundTruthState& s : groundtruth) {
    for (; jump != jumps.end() && jump->end_ns <= s.t_ns; ++jump) shift -= jump->excess_m;
    s.p_w_b += shift;
  }
  return groundtruth;
}

}  // namespace vio::tools
