#pragma once
// Motion sources of the simulator: a smooth analytic 6-DoF flight, and
// interpolation of a real ground-truth trajectory.
//
// The synthetic flight is a closed curve f(u) of the phase u in [0, 2 pi)
// (sums of sinusoids with integer frequencies in position and in yaw, pitch,
// roll; yaw also turns once per period) run through a time warp s(t):
//   s(t) = 0                                  t < T_static
//   s'(t) = h((t - T_static) / T_ramp)        during the ramp, h(x) = 35x^4 - 84x^5 + 70x^6 - 20x^7
//   s'(t) = 1                                 afterwards
//   u = 2 pi s / P.
// h has zero first to third derivatives at both ends, so position and
// attitude are C3 (in fact C4) everywhere and the flight starts at rest. The
// period P is the smallest one keeping |v| <= max speed and |omega| <= max
// rotation rate (both scale with 1 / P).
//
// Attitude: R_w_b = Rz(yaw) Ry(pitch) Rx(roll) R_r_b, where the constant
// R_r_b mounts the body as on the EuRoC MAV (IMU x up, z forward), so the
// cameras (looking along body z) look along the horizontal heading.
#include <optional>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "vio/estimator/types.h"
#include "vio/dataset/euroc_dataset.h"

namespace vio::tools {

/// Pose and derivatives of the body at one instant.
struct KinematicState {
  Eigen::Vector3d p_w_b = Eigen::Vector3d::Zero();            ///< [m]
  Eigen::Vector3d v_w_b = Eigen::Vector3d::Zero();            ///< [m/s]
  Eigen::Vector3d a_w_b = Eigen::Vector3d::Zero();            ///< [m/s^2]
  Eigen::Quaterniond q_w_b = Eigen::Quaterniond::Identity();  ///< Hamilton
  Eigen::Vector3d omega_b = Eigen::Vector3d::Zero();          ///< body angular rate [rad/s]
};

struct SyntheticTrajectoryOptions {
  /// Centre of the flight [m].
  Eigen::Vector3d center_w = Eigen::Vector3d(0.0, 0.0, 1.5);
  /// Largest excursion from the centre along x, y, z [m].
  Eigen::Vector3d half_extent_m = Eigen::Vector3d(2.5, 2.5, 0.8);
  /// Initial period at rest [s].
  double static_duration_s = 3.0;
  /// How far along the flight t = 0 is [s]: 0 starts at rest (the static
  /// period, then the ramp); static_duration_s + ramp_duration_s or more
  /// starts at full pace.
  double start_offset_s = 0.0;
  /// Smooth acceleration from rest to full pace [s].
  double ramp_duration_s = 2.0;
  /// Speed limit [m/s].
  double max_speed_m_s = 2.0;
  /// Angular rate limit [rad/s].
  double max_rotation_rate_rad_s = 1.5;
  /// Amplitude of the pitch and roll oscillations [rad].
  double tilt_amplitude_rad = 0.15;
};

class SyntheticTrajectory {
 public:
  /// Throws std::invalid_argument on non-positive limits or extents.
  explicit SyntheticTrajectory(const SyntheticTrajectoryOptions& options);

  /// The state at time t [s] since the start (t >= 0).
  KinematicState Evaluate(double t_s) const;

  /// One loop of the closed flight at full pace [s].
  double period_s() const { return period_s_; }

 private:
  struct Phase {  // the time warp: u and its first two time derivatives
    double u = 0.0, u_dot = 0.0, u_ddot = 0.0;
  };
  Phase WarpTime(double t_s) const;

  SyntheticTrajectoryOptions options_;
  double period_s_ = 1.0;
};

/// The EuRoC MAV mounting of the body in the trajectory's heading frame
/// (x forward, y left, z up): body x up, body z forward.
Eigen::Matrix3d HeadingFromBody();

/// Ground-truth pose at t, interpolated between the two neighbouring states
/// (slerp on rotation, linear on position); nullopt outside the span.
/// `groundtruth` must be sorted by time.
std::optional<Eigen::Isometry3d> InterpolatePose(const std::vector<GroundTruthState>& groundtruth,
                                                 Timestamp t_ns);

/// A ground-truth step whose displacement disagrees with the ground truth's
/// own velocity: a glitch of the reference (EuRoC MH_04_difficult has one of
/// 14 cm in 5 ms). A hybrid simulation that kept it would move its cameras
/// with it while the real IMU does not; RemoveGroundTruthJumps takes it out.
struct GroundTruthJump {
  Timestamp t_ns = 0;        ///< start of the step (t_a)
  Timestamp end_ns = 0;      ///< end of the step (t_b): the first sample after the jump
  double step_m = 0.0;       ///< |p(t_b) - p(t_a)| [m]
  double speed_m_s = 0.0;    ///< step_m / (t_b - t_a) [m/s]
  double velocity_m_s = 0.0; ///< |v(t_a) + v(t_b)| / 2 from the ground truth [m/s]
  /// What the step moved beyond the ground truth's own velocity:
  /// (p_b - p_a) - (v_a + v_b) / 2 (t_b - t_a), world frame [m].
  Eigen::Vector3d excess_m = Eigen::Vector3d::Zero();
};

/// The steps where |(p_b - p_a) / (t_b - t_a) - (v_a + v_b) / 2| exceeds
/// tolerance_m_s; none for a ground truth without velocities (TUM).
std::vector<GroundTruthJump> FindGroundTruthJumps(const std::vector<GroundTruthState>& groundtruth,
                                                  double tolerance_m_s);

/// The ground truth without its jumps: every sample from a jump's end on is
/// moved by -excess_m, so each step agrees with the ground truth's velocity
/// again. Orientations, velocities and biases are kept; so is a jump's
/// share the velocity explains. `jumps` from FindGroundTruthJumps on the
/// same ground truth.
std::vector<GroundTruthState> RemoveGroundTruthJumps(std::vector<GroundTruthState> groundtruth,
                                                     const std::vector<GroundTruthJump>& jumps);

}  // namespace vio::tools
