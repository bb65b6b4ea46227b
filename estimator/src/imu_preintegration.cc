#include "vio/estimator/imu_preintegration.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <glog/logging.h>

#include "vio/estimator/so3.h"
#include "imu_state_index.h"

namespace vio {
namespace {

using Matrix15d = ImuPreintegration::Matrix15d;
using imu_state_index::kBa;
using imu_state_index::kBg;
using imu_state_index::kP;
using imu_state_index::kR;
using imu_state_index::kV;

/// The linearization of one midpoint step, error_{k+1} = F error_k + G n with
/// n = [n_g, n_a, n_bg, n_ba], by its non-zero 3 x 3 blocks (F is the
/// identity elsewhere; G's measurement-noise columns are F's bias columns, its
/// random-walk columns the identity on the bias rows):
///   F_R = [dR^T, 0, 0, -Jr dt, 0]
///   F_V = [dv_dphi, I, 0, dv_dbg, dv_dba]
///   F_P = [dp_dphi, I dt, I, dp_dbg, dp_dba]
struct StepLinearization {
  Eigen::Matrix3d dR_transpose;
  Eigen::Matrix3d minus_Jr_dt;
  Eigen::Matrix3d dv_dphi, dv_dbg, dv_dba;
  Eigen::Matrix3d dp_dphi, dp_dbg, dp_dba;
  double dt = 0.0;

  /// F X, on F's non-zero blocks only (a dense 15 x 15 product costs about 5x as much).
  Matrix15d Times(const Matrix15d& X) const {
    Matrix15d Y;
    const auto x_r = X.middleRows<3>(kR);
    const auto x_bg = X.middleRows<3>(kBg);
    const auto x_ba = X.middleRows<3>(kBa);
    Y.middleRows<3>(kR).noalias() = dR_transpose * x_r;
    Y.middleRows<3>(kR).noalias() += minus_Jr_dt * x_bg;
    Y.middleRows<3>(kV) = X.middleRows<3>(kV);
    Y.middleRows<3>(kV).noalias() += dv_dphi * x_r;
    Y.middleRows<3>(kV).noalias() += dv_dbg * x_bg;
    Y.middleRows<3>(kV).noalias() += dv_dba * x_ba;
    Y.middleRows<3>(kP) = X.middleRows<3>(kP) + dt * X.middleRows<3>(kV);
    Y.middleRows<3>(kP).noalias() += dp_dphi * x_r;
    Y.middleRows<3>(kP).noalias() += dp_dbg * x_bg;
    Y.middleRows<3>(kP).noalias() += dp_dba * x_ba;
    Y.middleRows<6>(kBg) = X.middleRows<6>(kBg);
    return Y;
  }

  /// G diag(q) G^T added to `covariance` for the noise variances q (each the
  /// same on its three axes): the measurement noise through F's bias columns,
  /// the random walks on the bias rows.
  void AddNoise(double gyro, double accel, double gyro_walk, double accel_walk, Matrix15d* covariance) const {
    static_assert(kV == kR + 3 && kP == kV + 3, "rotation, velocity and position rows are contiguous");
    Eigen::Matrix<double, 9, 3> g_gyro;
    g_gyro << minus_Jr_dt, dv_dbg, dp_dbg;
    Eigen::Matrix<double, 6, 3> g_accel;
    g_accel << dv_dba, dp_dba;
    covariance->block<9, 9>(kR, kR).noalias() += gyro * g_gyro * g_gyro.transpose();
    covariance->block<6, 6>(kV, kV).noalias() += accel * g_accel * g_accel.transpose();
    covariance->block<3, 3>(kBg, kBg).diagonal().array() += gyro_walk;
    covariance->block<3, 3>(kBa, kBa).diagonal().array() += accel_walk;
  }
};

/// F and G of one step (see the header comment for the step itself):
///   dphi' = dR^T dphi - Jr dt (db_g + n_g)
///   dacc  = -1/2 R_k [a_a]x dphi - 1/2 R_k1 [a_b]x dphi' - 1/2 (R_k + R_k1)(db_a + n_a)
///   dv'   = dv + dacc dt,   dp' = dp + dv dt + dacc dt^2 / 2
///   db'   = db + n_b
StepLinearization LinearizeStep(const Eigen::Matrix3d& R_k, const Eigen::Matrix3d& R_k1,
                                const Eigen::Vector3d& theta, const Eigen::Vector3d& accel_a,
                                const Eigen::Vector3d& accel_b, double dt) {
  const Eigen::Matrix3d dR_transpose = so3::Exp(theta).transpose();
  const Eigen::Matrix3d Jr_dt = so3::RightJacobian(theta) * dt;
  const Eigen::Matrix3d R_k1_accel_b_hat = R_k1 * so3::Hat(accel_b);
  const Eigen::Matrix3d dacc_dphi =
      -0.5 * R_k * so3::Hat(accel_a) - 0.5 * R_k1_accel_b_hat * dR_transpose;
  const Eigen::Matrix3d dacc_dbg = 0.5 * R_k1_accel_b_hat * Jr_dt;
  const Eigen::Matrix3d dacc_dba = -0.5 * (R_k + R_k1);

  StepLinearization lin;
  lin.dR_transpose = dR_transpose;
  lin.minus_Jr_dt = -Jr_dt;
  lin.dv_dphi = dacc_dphi * dt;
  lin.dv_dbg = dacc_dbg * dt;
  lin.dv_dba = dacc_dba * dt;
  lin.dp_dphi = 0.5 * dacc_dphi * dt * dt;
  lin.dp_dbg = 0.5 * dacc_dbg * dt * dt;
  lin.dp_dba = 0.5 * dacc_dba * dt * dt;
  lin.dt = dt;
  return lin;
}

}  // namespace

ImuPreintegration::ImuPreintegration(const ImuBias& linearization_bias,
                                     const ImuCalibration& calibration)
    : linearization_bias_(linearization_bias),
      gyro_noise_density_(calibration.gyro_noise_density),
      accel_noise_density_(calibration.accel_noise_density),
      gyro_random_walk_(calibration.gyro_random_walk),
      accel_random_walk_(calibration.accel_random_walk) {
  if (!calibration.T_b_i.isApprox(Eigen::Isometry3d::Identity(), 1e-9)) {
    throw std::invalid_argument(
        "ImuPreintegration: ImuCalibration::T_b_i must be the identity (body = IMU)");
  }
}

void ImuPreintegration::Integrate(const ImuSample& a, const ImuSample& b) {
  CHECK_GT(b.t_ns, a.t_ns) << "IMU samples must be strictly increasing in time";
  const Step step{NanosToSeconds(b.t_ns - a.t_ns), a.gyro_rad_s, b.gyro_rad_s, a.accel_m_s2,
                  b.accel_m_s2};
  steps_.push_back(step);
  Propagate(step);
}

void ImuPreintegration::Integrate(double dt_s, const Eigen::Vector3d& gyro_rad_s,
                                  const Eigen::Vector3d& accel_m_s2) {
  CHECK_GT(dt_s, 0.0) << "IMU integration step must be positive";
  const Step step{dt_s, gyro_rad_s, gyro_rad_s, accel_m_s2, accel_m_s2};
  steps_.push_back(step);
  Propagate(step);
}

void ImuPreintegration::Append(const ImuPreintegration& next) {
  for (const Step& step : next.steps_) {
    steps_.push_back(step);
    Propagate(step);
  }
}

void ImuPreintegration::Reintegrate(const ImuBias& new_linearization_bias) {
  linearization_bias_ = new_linearization_bias;
  Reset();
  for (const Step& step : steps_) Propagate(step);
}

bool ImuPreintegration::NeedsReintegration(const ImuBias& bias, double gyro_threshold_rad_s,
                                           double accel_threshold_m_s2) const {
  const double gyro_change = (bias.gyro - linearization_bias_.gyro).cwiseAbs().maxCoeff();
  const double accel_change = (bias.accel - linearization_bias_.accel).cwiseAbs().maxCoeff();
  return gyro_change > gyro_threshold_rad_s || accel_change > accel_threshold_m_s2;
}

ImuPreintegration::Deltas ImuPreintegration::CorrectedDeltas(const ImuBias& bias) const {
  const Eigen::Vector3d dbg = bias.gyro - linearization_bias_.gyro;
  const Eigen::Vector3d dba = bias.accel - linearization_bias_.accel;
  Deltas corrected;
  corrected.delta_q = (deltas_.delta_q * so3::ExpQuaternion(d_delta_R_d_bg() * dbg)).normalized();
  corrected.delta_v = deltas_.delta_v + d_delta_v_d_bg() * dbg + d_delta_v_d_ba() * dba;
  corrected.delta_p = deltas_.delta_p + d_delta_p_d_bg() * dbg + d_delta_p_d_ba() * dba;
  return corrected;
}

ImuPreintegration::Matrix15d ImuPreintegration::SqrtInformation() const {
  CHECK(!steps_.empty()) << "SqrtInformation of an empty preintegration";
  const Matrix15d symmetric = 0.5 * (covariance_ + covariance_.transpose());
  const Eigen::LLT<Matrix15d> covariance_llt(symmetric);
  if (covariance_llt.info() == Eigen::Success) {
    const Matrix15d information = covariance_llt.solve(Matrix15d::Identity());
    const Eigen::LLT<Matrix15d> llt(0.5 * (information + information.transpose()));
    if (llt.info() == Eigen::Success && llt.matrixU().toDenseMatrix().allFinite()) return llt.matrixU();
  }
  return SqrtInformationByEigen(symmetric);
}

// A long IMU gap (or extreme values) leaves a covariance too ill-conditioned
// for Cholesky: W = Lambda^-1/2 V^T with the eigenvalues floored at a
// fraction of the largest, so W^T W is the (regularized) information.
ImuPreintegration::Matrix15d ImuPreintegration::SqrtInformationByEigen(const Matrix15d& covariance) {
  constexpr double kRelativeFloor = 1e-9;
  CHECK(covariance.allFinite()) << "IMU preintegration covariance is not finite (IMU values are range-checked)";
  const Eigen::SelfAdjointEigenSolver<Matrix15d> eigen(covariance);
  const double floor = std::max(eigen.eigenvalues().cwiseAbs().maxCoeff() * kRelativeFloor,
                                std::numeric_limits<double>::min());
  const Eigen::Matrix<double, 15, 1> inverse_sqrt =
      eigen.eigenvalues().cwiseMax(floor).cwiseSqrt().cwiseInverse();
  return inverse_sqrt.asDiagonal() * eigen.eigenvectors().transpose();
}

void ImuPreintegration::Reset() {
  deltas_ = Deltas();
  delta_time_s_ = 0.0;
  covariance_.setZero();
  jacobian_.setIdentity();
}

void ImuPreintegration::Propagate(const Step& step) {
  const double dt = step.dt_s;
  const Eigen::Vector3d omega =
      0.5 * (step.gyro_a + step.gyro_b) - linearization_bias_.gyro;
  const Eigen::Vector3d accel_a = step.accel_a - linearization_bias_.accel;
  const Eigen::Vector3d accel_b = step.accel_b - linearization_bias_.accel;
  const Eigen::Vector3d theta = omega * dt;

  const Eigen::Quaterniond q_k1 = (deltas_.delta_q * so3::ExpQuaternion(theta)).normalized();
  const Eigen::Matrix3d R_k = deltas_.delta_q.toRotationMatrix();
  const Eigen::Matrix3d R_k1 = q_k1.toRotationMatrix();
  const Eigen::Vector3d acc = 0.5 * (R_k * accel_a + R_k1 * accel_b);

  const StepLinearization lin = LinearizeStep(R_k, R_k1, theta, accel_a, accel_b, dt);
  // F P F^T = F (F P)^T, P symmetric.
  covariance_ = lin.Times(lin.Times(covariance_).transpose());
  lin.AddNoise(gyro_noise_density_ * gyro_noise_density_ / dt, accel_noise_density_ * accel_noise_density_ / dt,
               gyro_random_walk_ * gyro_random_walk_ * dt, accel_random_walk_ * accel_random_walk_ * dt, &covariance_);
  jacobian_ = lin.Times(jacobian_);

  deltas_.delta_p += deltas_.delta_v * dt + 0.5 * acc * dt * dt;
  deltas_.delta_v += acc * dt;
  deltas_.delta_q = q_k1;
  delta_time_s_ += dt;
}

ImuSample InterpolateImuSample(const ImuSample& a, const ImuSample& b, Timestamp t_ns) {
  CHECK_LT(a.t_ns, b.t_ns);
  CHECK(a.t_ns <= t_ns && t_ns <= b.t_ns) << "interpolation time outside [a, b]";
  const double s = static_cast<double>(t_ns - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
  ImuSample sample;
  sample.t_ns = t_ns;
  sample.gyro_rad_s = (1.0 - s) * a.gyro_rad_s + s * b.gyro_rad_s;
  sample.accel_m_s2 = (1.0 - s) * a.accel_m_s2 + s * b.accel_m_s2;
  return sample;
}

namespace {

[[noreturn]] void ThrowBadImuRange(const std::string& what, Timestamp t0_ns, Timestamp t1_ns) {
  std::ostringstream message;
  message << "PreintegrateBetween(t0=" << t0_ns << " ns, t1=" << t1_ns << " ns): " << what;
  throw std::invalid_argument(message.str());
}

}  // namespace

ImuPreintegration PreintegrateBetween(const std::vector<ImuSample>& samples, Timestamp t0_ns,
                                      Timestamp t1_ns, const ImuBias& linearization_bias,
                                      const ImuCalibration& calibration) {
  if (t1_ns <= t0_ns) ThrowBadImuRange("t1 must be after t0", t0_ns, t1_ns);
  if (samples.empty() || samples.front().t_ns > t0_ns || samples.back().t_ns < t1_ns) {
    ThrowBadImuRange("IMU samples do not cover the interval", t0_ns, t1_ns);
  }
  const auto later_than_t0 = std::upper_bound(
      samples.begin(), samples.end(), t0_ns,
      [](Timestamp t, const ImuSample& sample) { return t < sample.t_ns; });
  ImuPreintegration preintegration(linearization_bias, calibration);
  ImuSample previous = InterpolateImuSample(*(later_than_t0 - 1), *later_than_t0, t0_ns);
  for (auto it = later_than_t0; it != samples.end(); ++it) {
    if (it->t_ns <= (it - 1)->t_ns) ThrowBadImuRange("IMU stamps not increasing", t0_ns, t1_ns);
    const bool last = it->t_ns >= t1_ns;
    const ImuSample next = last ? InterpolateImuSample(*(it - 1), *it, t1_ns) : *it;
    preintegration.Integrate(previous, next);
    if (last) break;
    previous = next;
  }
  return preintegration;
}

}  // namespace vio
