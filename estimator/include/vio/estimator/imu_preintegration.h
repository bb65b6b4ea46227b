#pragma once
// IMU preintegration on the manifold (Forster et al. 2017, "On-Manifold
// Preintegration for Real-Time Visual-Inertial Odometry"), with bias
// Jacobians, a 15x15 covariance including the bias random walk, and
// reintegration from the stored samples.
//
// Measurement model (body = IMU): gyro = w_b + b_g + n_g,
// accel = R_w_b^T (a_w - g_w) + b_a + n_a.
//
// Integration scheme: midpoint. One step between samples a and b (dt > 0,
// irregular dt allowed) with the linearization bias (b_g, b_a):
//   w   = (gyro_a + gyro_b) / 2 - b_g
//   dR  = Exp(w dt),            R_{k+1} = R_k dR
//   acc = ((R_k (accel_a - b_a)) + (R_{k+1} (accel_b - b_a))) / 2
//   p_{k+1} = p_k + v_k dt + acc dt^2 / 2,   v_{k+1} = v_k + acc dt
// (R, v, p) = (delta_R, delta_v, delta_p) start at (I, 0, 0). The scheme is
// exact for a constant body rate and a constant world acceleration.
//
// Error state (also the IMU residual order): [dphi (right perturbation of
// delta_R), dv, dp, db_g, db_a] (15). Each step propagates
//   Sigma <- F Sigma F^T + G Q G^T,  J <- F J
// with F, G the exact linearization of the step above (J starts at I), noise
// n = [n_g, n_a, n_bg, n_ba] and discrete covariance
//   Q = diag(sigma_g^2 / dt, sigma_a^2 / dt, sigma_bg^2 dt, sigma_ba^2 dt)
// from the continuous densities of ImuCalibration. The bias Jacobians are the
// blocks J(rows R/v/p, cols b_g/b_a), the exact derivatives of the discrete
// integration with respect to the bias.
//
// Bias correction to first order (Forster eq. 44), db = b - b_lin:
//   delta_R(b) = delta_R Exp(dR/dbg db_g)
//   delta_v(b) = delta_v + dv/dbg db_g + dv/dba db_a
//   delta_p(b) = delta_p + dp/dbg db_g + dp/dba db_a
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "vio/estimator/types.h"

namespace vio {

/// IMU biases.
struct ImuBias {
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();   ///< b_g [rad/s]
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();  ///< b_a [m/s^2]
};

/// Preintegrated relative motion between two frames.
class ImuPreintegration {
 public:
  using Matrix15d = Eigen::Matrix<double, 15, 15>;

  /// Offsets of the blocks of the 15-dim error state / IMU residual.
  static constexpr int kRotation = 0;
  static constexpr int kVelocity = 3;
  static constexpr int kPosition = 6;
  static constexpr int kBiasGyro = 9;
  static constexpr int kBiasAccel = 12;
  static constexpr int kErrorSize = 15;

  /// The preintegrated deltas (optionally bias-corrected).
  struct Deltas {
    Eigen::Quaterniond delta_q = Eigen::Quaterniond::Identity();  ///< delta_R
    Eigen::Vector3d delta_v = Eigen::Vector3d::Zero();            ///< [m/s]
    Eigen::Vector3d delta_p = Eigen::Vector3d::Zero();            ///< [m]
  };

  /// Empty preintegration linearized at `linearization_bias`, with the noise
  /// densities of `calibration`. Throws std::invalid_argument unless
  /// calibration.T_b_i is the identity (body = IMU).
  ImuPreintegration(const ImuBias& linearization_bias, const ImuCalibration& calibration);

  /// Integrates from sample a to sample b (midpoint); b.t_ns > a.t_ns.
  void Integrate(const ImuSample& a, const ImuSample& b);
  /// Integrates one step of dt_s > 0 [s] with the readings held constant.
  void Integrate(double dt_s, const Eigen::Vector3d& gyro_rad_s, const Eigen::Vector3d& accel_m_s2);
  /// Appends the stored steps of `next` (integrated at this linearization
  /// bias): the preintegration over both intervals.
  void Append(const ImuPreintegration& next);
  /// Redoes the whole integration from the stored steps at a new
  /// linearization bias.
  void Reintegrate(const ImuBias& new_linearization_bias);
  /// True when `bias` is farther from the linearization bias than a threshold
  /// (max-norm per component) so that the first-order correction should be
  /// replaced by Reintegrate(bias).
  bool NeedsReintegration(const ImuBias& bias, double gyro_threshold_rad_s,
                          double accel_threshold_m_s2) const;

  /// Deltas at the linearization bias.
  const Deltas& deltas() const { return deltas_; }
  /// Deltas corrected to first order for `bias` (Forster eq. 44).
  Deltas CorrectedDeltas(const ImuBias& bias) const;

  double delta_time_s() const { return delta_time_s_; }  ///< integrated time [s]
  int num_steps() const { return static_cast<int>(steps_.size()); }
  const ImuBias& linearization_bias() const { return linearization_bias_; }
  /// Covariance of [dphi, dv, dp, db_g, db_a] (bias rows: random walk).
  const Matrix15d& covariance() const { return covariance_; }
  /// S with S^T S = covariance()^-1 (whitens residuals): upper-triangular
  /// (Cholesky), or from the eigen-decomposition with the eigenvalues floored
  /// when a long IMU gap makes the covariance too ill-conditioned for it;
  /// requires num_steps() > 0.
  Matrix15d SqrtInformation() const;

  Eigen::Matrix3d d_delta_R_d_bg() const { return Block(kRotation, kBiasGyro); }
  Eigen::Matrix3d d_delta_v_d_bg() const { return Block(kVelocity, kBiasGyro); }
  Eigen::Matrix3d d_delta_v_d_ba() const { return Block(kVelocity, kBiasAccel); }
  Eigen::Matrix3d d_delta_p_d_bg() const { return Block(kPosition, kBiasGyro); }
  Eigen::Matrix3d d_delta_p_d_ba() const { return Block(kPosition, kBiasAccel); }

 private:
  /// One stored integration step (the readings at both ends).
  struct Step {
    double dt_s = 0.0;
    Eigen::Vector3d gyro_a, gyro_b, accel_a, accel_b;
  };

  static Matrix15d SqrtInformationByEigen(const Matrix15d& covariance);
  void Reset();
  void Propagate(const Step& step);
  Eigen::Matrix3d Block(int row, int col) const { return jacobian_.block<3, 3>(row, col); }

  ImuBias linearization_bias_;
  /// Continuous-time noise densities and random walks copied from ImuCalibration.
  double gyro_noise_density_, accel_noise_density_, gyro_random_walk_, accel_random_walk_;
  std::vector<Step> steps_;
  Deltas deltas_;
  double delta_time_s_ = 0.0;
  Matrix15d covariance_ = Matrix15d::Zero();
  Matrix15d jacobian_ = Matrix15d::Identity();  ///< d(error state) / d(start error state)
};

/// Linear interpolation of the readings of a and b at t_ns (a.t_ns <= t_ns <=
/// b.t_ns, a.t_ns < b.t_ns).
ImuSample InterpolateImuSample(const ImuSample& a, const ImuSample& b, Timestamp t_ns);

/// Preintegrates the samples over [t0_ns, t1_ns]: the readings at t0_ns and
/// t1_ns are interpolated linearly between their neighbouring samples.
/// `samples` must be sorted by time with strictly increasing stamps inside
/// the interval and must cover it (front <= t0_ns, back >= t1_ns); otherwise
/// throws std::invalid_argument naming the times.
ImuPreintegration PreintegrateBetween(const std::vector<ImuSample>& samples, Timestamp t0_ns,
                                      Timestamp t1_ns, const ImuBias& linearization_bias,
                                      const ImuCalibration& calibration);

}  // namespace vio
