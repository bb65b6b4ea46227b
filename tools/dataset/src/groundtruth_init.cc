#include "vio/dataset/groundtruth_init.h"

#include <algorithm>
#include <cmath>

#include <glog/logging.h>

#include "vio/estimator/so3.h"

namespace vio::tools {
namespace {

/// Central-difference step on the ground truth [ns] (EuRoC's is 200 Hz).
constexpr Timestamp kStepNs = 25'000'000;

struct DifferencedMotion {
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();
  int samples = 0;
};

// IMU minus the motion of the ground truth, averaged over the samples whose
// differences stay inside the ground-truth span.
DifferencedMotion MeanImuResidual(const std::vector<GroundTruthState>& gt, const std::vector<ImuSample>& imu,
                                  Timestamp from_ns, Timestamp to_ns, double gravity_m_s2) {
  DifferencedMotion mean;
  const double h = static_cast<double>(kStepNs) * 1e-9;
  auto first = std::lower_bound(imu.begin(), imu.end(), from_ns,
                                [](const ImuSample& s, Timestamp t) { return s.t_ns < t; });
  for (auto sample_it = first; sample_it != imu.end() && sample_it->t_ns <= to_ns; ++sample_it) {
    const ImuSample& sample = *sample_it;
    const auto before = InterpolateGroundTruth(gt, sample.t_ns - kStepNs);
    const auto at = InterpolateGroundTruth(gt, sample.t_ns);
    const auto after = InterpolateGroundTruth(gt, sample.t_ns + kStepNs);
    if (!before || !at || !after) continue;
    const Eigen::Vector3d w_b = so3::Log(before->q_w_b.conjugate() * after->q_w_b) / (2 * h);
    const Eigen::Vector3d a_w = (after->p_w_b - 2 * at->p_w_b + before->p_w_b) / (h * h);
    mean.gyro_bias += sample.gyro_rad_s - w_b;
    mean.accel_bias += sample.accel_m_s2 - at->q_w_b.conjugate() * (a_w + gravity_m_s2 * Eigen::Vector3d::UnitZ());
    ++mean.samples;
  }
  if (mean.samples > 0) {
    mean.gyro_bias /= mean.samples;
    mean.accel_bias /= mean.samples;
  }
  return mean;
}

}  // namespace

std::optional<GroundTruthState> InterpolateGroundTruth(const std::vector<GroundTruthState>& gt, Timestamp t_ns) {
  auto it = std::lower_bound(gt.begin(), gt.end(), t_ns,
                             [](const GroundTruthState& s, Timestamp t) { return s.t_ns < t; });
  if (it == gt.end() || (it == gt.begin() && it->t_ns != t_ns)) return std::nullopt;
  const GroundTruthState& b = *it;
  const GroundTruthState& a = it == gt.begin() ? b : *(it - 1);
  const double s = b.t_ns == a.t_ns ? 0.0 : static_cast<double>(t_ns - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
  GroundTruthState state = b;
  state.t_ns = t_ns;
  state.p_w_b = (1 - s) * a.p_w_b + s * b.p_w_b;
  state.q_w_b = a.q_w_b.slerp(s, b.q_w_b);
  state.v_w_b = (1 - s) * a.v_w_b + s * b.v_w_b;
  state.gyro_bias = (1 - s) * a.gyro_bias + s * b.gyro_bias;
  state.accel_bias = (1 - s) * a.accel_bias + s * b.accel_bias;
  return state;
}

std::optional<InitialState> GroundTruthInitialState(const std::vector<GroundTruthState>& gt,
                                                    const std::vector<ImuSample>& imu, Timestamp t_ns,
                                                    double gravity_m_s2, double span_s) {
  const std::optional<GroundTruthState> at = InterpolateGroundTruth(gt, t_ns);
  if (!at) return std::nullopt;
  InitialState state{t_ns, at->p_w_b, at->q_w_b, at->v_w_b, at->gyro_bias, at->accel_bias};
  if (at->has_velocity_and_biases) return state;

  const auto before = InterpolateGroundTruth(gt, t_ns - kStepNs);
  const auto after = InterpolateGroundTruth(gt, t_ns + kStepNs);
  const GroundTruthState& from = before ? *before : *at;
  const GroundTruthState& to = after ? *after : *at;
  if (to.t_ns > from.t_ns) state.v_w_b = (to.p_w_b - from.p_w_b) / (static_cast<double>(to.t_ns - from.t_ns) * 1e-9);
  const auto span_ns = static_cast<Timestamp>(span_s * 1e9);
  const DifferencedMotion mean = MeanImuResidual(gt, imu, t_ns - span_ns, t_ns + span_ns, gravity_m_s2);
  if (mean.samples == 0) {
    LOG(WARNING) << "ground-truth start at t=" << static_cast<double>(t_ns) * 1e-9
                 << " s: no IMU samples inside the ground truth to derive the biases from; starting from zero biases";
    return state;
  }
  state.gyro_bias = mean.gyro_bias;
  state.accel_bias = mean.accel_bias;
  LOG(INFO) << "ground-truth start from poses only: velocity " << state.v_w_b.transpose() << " m/s, gyro bias "
            << state.gyro_bias.transpose() << " rad/s, accel bias " << state.accel_bias.transpose()
            << " m/s^2 (from " << mean.samples << " IMU samples)";
  return state;
}

std::optional<double> GroundTruthTiltDeg(const std::vector<GroundTruthState>& gt, const std::vector<ImuSample>& imu,
                                         double gravity_m_s2) {
  if (gt.empty() || imu.empty()) return std::nullopt;
  // The specific force in the world is a_w + g e_z; averaged, the motion cancels.
  constexpr size_t kMaxSamples = 2000;
  const size_t stride = std::max<size_t>(1, imu.size() / kMaxSamples);
  const double h = static_cast<double>(kStepNs) * 1e-9;
  Eigen::Vector3d up_sum = Eigen::Vector3d::Zero();
  int count = 0;
  for (size_t i = 0; i < imu.size(); i += stride) {
    const Timestamp t = imu[i].t_ns;
    const auto before = InterpolateGroundTruth(gt, t - kStepNs);
    const auto at = InterpolateGroundTruth(gt, t);
    const auto after = InterpolateGroundTruth(gt, t + kStepNs);
    if (!before || !at || !after) continue;
    const Eigen::Vector3d a_w = (after->p_w_b - 2 * at->p_w_b + before->p_w_b) / (h * h);
    up_sum += at->q_w_b * imu[i].accel_m_s2 - a_w;
    ++count;
  }
  if (count == 0 || up_sum.norm() < 0.5 * gravity_m_s2 * count) return std::nullopt;
  const double cos_tilt = std::clamp(up_sum.normalized().z(), -1.0, 1.0);
  return std::acos(cos_tilt) * 180.0 / M_PI;
}

}  // namespace vio::tools
