#pragma once
// Visual-inertial alignment of a stereo trajectory (dynamic initialization):
// given body poses T_0_k in the first frame's body (metric, from stereo) and
// the IMU preintegrated between consecutive frames, solves for
//   * the gyro bias: the preintegrated rotations aligned to the stereo ones,
//     to first order in the bias (Forster eq. 44), least squares;
//   * per-frame velocities, gravity and the accel bias, linear in them
//     (Forster's delta-v / delta-p equations with the positions known):
//       v_k - v_{k-1} - g dt - R_{k-1} dv/dba b_a             = R_{k-1} delta_v
//       v_{k-1} dt + g dt^2 / 2 + R_{k-1} dp/dba b_a          = p_k - p_{k-1} - R_{k-1} delta_p
//     with a zero-mean prior on b_a (unobservable without rotation), first
//     with g free, then with |g| fixed by Gauss-Newton on the sphere of its
//     direction (two tangent unknowns), as in VINS-Mono's RefineGravity.
// Everything is in the first frame's body coordinates.
#include <string>
#include <vector>

#include "vio/estimator/imu_preintegration.h"
#include "vio/estimator/types.h"

namespace vio {

/// The gyro bias aligning the preintegrations (k-1 -> k, one per interval) to the
/// rotations of T_0_k: the linearization bias plus the least-squares correction.
Eigen::Vector3d AlignGyroBias(const std::vector<Eigen::Isometry3d>& T_0_k,
                              const std::vector<ImuPreintegration>& preintegrations);

struct VelocityGravity {
  std::vector<Eigen::Vector3d> v_0;  ///< velocity of each frame, in frame 0 [m/s]
  Eigen::Vector3d g_0 = Eigen::Vector3d::Zero();  ///< gravity in frame 0, |g_0| = gravity [m/s^2]
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();  ///< [m/s^2]
  double free_gravity_norm = 0;  ///< |g| of the solve with g free [m/s^2] (a consistency check)
};

/// Solves the linear system above. accel_bias_sigma: the prior on b_a [m/s^2]; position_sigma_m:
/// the noise of each stereo position [m] (weights the delta-p rows against the preintegration's).
VelocityGravity AlignVelocityGravity(const std::vector<Eigen::Isometry3d>& T_0_k,
                                     const std::vector<ImuPreintegration>& preintegrations, double gravity,
                                     double accel_bias_sigma, double position_sigma_m);

}  // namespace vio
