#include "vio/estimator/initializer.h"

#include <cmath>
#include <sstream>

namespace vio {
namespace {

constexpr double kMinCoveredFraction = 0.9;

struct ImuStatistics {
  int count = 0;
  Timestamp first_ns = 0;  // first and last sample in the window
  Timestamp last_ns = 0;
  Eigen::Vector3d gyro_mean = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_mean = Eigen::Vector3d::Zero();
  double gyro_std = 0;   // RMS over axes of the per-axis standard deviation
  double accel_std = 0;
};

ImuStatistics Statistics(const std::vector<ImuSample>& imu, Timestamp t0, Timestamp t1) {
  ImuStatistics s;
  Eigen::Vector3d gyro_sq = Eigen::Vector3d::Zero(), accel_sq = Eigen::Vector3d::Zero();
  for (const ImuSample& m : imu) {
    if (m.t_ns < t0 || m.t_ns > t1) continue;
    if (s.count == 0) s.first_ns = m.t_ns;
    s.last_ns = m.t_ns;
    ++s.count;
    s.gyro_mean += m.gyro_rad_s;
    s.accel_mean += m.accel_m_s2;
    gyro_sq += m.gyro_rad_s.cwiseAbs2();
    accel_sq += m.accel_m_s2.cwiseAbs2();
  }
  if (s.count == 0) return s;
  s.gyro_mean /= s.count;
  s.accel_mean /= s.count;
  s.gyro_std = std::sqrt(std::max(0.0, (gyro_sq / s.count - s.gyro_mean.cwiseAbs2()).sum()));
  s.accel_std = std::sqrt(std::max(0.0, (accel_sq / s.count - s.accel_mean.cwiseAbs2()).sum()));
  return s;
}

}  // namespace

StaticInitResult InitializeStatic(const std::vector<ImuSample>& imu, Timestamp t_ns, const InitOptions& options) {
  const Timestamp t0 = t_ns - SecondsToNanos(options.static_window_s);
  const ImuStatistics s = Statistics(imu, t0, t_ns);
  std::ostringstream why;
  if (s.count < 10) {
    why << "only " << s.count << " IMU samples in the " << options.static_window_s << " s before t="
        << NanosToSeconds(t_ns) << " s";
    return {std::nullopt, why.str()};
  }
  // Motion is judged on the samples there are: a start in motion is known
  // as one before the window is full.
  if (s.gyro_std > options.static_max_gyro_std || s.accel_std > options.static_max_accel_std) {
    why << "the IMU is moving at t=" << NanosToSeconds(t_ns) << " s (gyro std " << s.gyro_std << " rad/s, limit "
        << options.static_max_gyro_std << "; accel std " << s.accel_std << " m/s^2, limit "
        << options.static_max_accel_std << ")";
    return {std::nullopt, why.str(), /*moving=*/true};
  }
  // The samples must span the window asked for (a few periods short at most),
  // not just its last tenth.
  const double covered_s = NanosToSeconds(s.last_ns - s.first_ns);
  if (covered_s < kMinCoveredFraction * options.static_window_s) {
    why << "the IMU does not cover " << kMinCoveredFraction * 100 << "% of the " << options.static_window_s
        << " s static window before the frame yet";
    return {std::nullopt, why.str()};
  }
  InitialState state;
  state.t_ns = t_ns;
  // At rest the accelerometer measures R_w_b^T (0, 0, g): rotate its mean onto +z.
  state.q_w_b = Eigen::Quaterniond::FromTwoVectors(s.accel_mean.normalized(), Eigen::Vector3d::UnitZ());
  state.gyro_bias = s.gyro_mean;
  return {state, "", false, s.accel_mean};
}

}  // namespace vio
