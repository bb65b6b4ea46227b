// Absolute trajectory error (ATE) and relative pose error (RPE).
//
// ATE, per aligned pose i:  e_p = |p_est_i - p_gt_i|,  e_R = angle(R_gt_i^T R_est_i);
//   reported as RMS / mean / median / max of e_p and RMS of e_R.
// RPE over length L, with d_k the ground-truth path length from pose 0 to k:
//   for each i, j = min { j > i : d_j - d_i >= L };
//   E = (T_gt_i^-1 T_gt_j)^-1 (T_est_i^-1 T_est_j);
//   trans_pct = mean |t(E)| / L * 100,  rot_deg_per_m = mean angle(E) / L.
// angle(R) = 2 atan2(|q.vec|, |q.w|) for the quaternion q of R, in [0, pi].
#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "vio/evaluation/trajectory_eval.h"

namespace vio::tools {
namespace {

constexpr double kRadToDeg = 180.0 / EIGEN_PI;

double RotationAngleRad(const Eigen::Matrix3d& R) {
  const Eigen::Quaterniond q(R);
  return 2.0 * std::atan2(q.vec().norm(), std::abs(q.w()));
}

double Rms(const std::vector<double>& values) {
  double sum_sq = 0.0;
  for (double v : values) sum_sq += v * v;
  return std::sqrt(sum_sq / static_cast<double>(values.size()));
}

double Median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

// d_k: ground-truth path length from the first pose to pose k [m].
std::vector<double> PathLength(const std::vector<Eigen::Isometry3d>& T_w_b) {
  std::vector<double> distance(T_w_b.size(), 0.0);
  for (size_t k = 1; k < T_w_b.size(); ++k) {
    distance[k] = distance[k - 1] + (T_w_b[k].translation() - T_w_b[k - 1].translation()).norm();
  }
  return distance;
}

RpeResult RpeAtLength(const AssociatedTrajectory& aligned, const std::vector<double>& distance,
                      double length_m) {
  RpeResult result;
  result.length_m = length_m;
  double sum_trans_m = 0.0;
  double sum_rot_rad = 0.0;
  for (size_t i = 0; i < distance.size(); ++i) {
    const auto j_it = std::lower_bound(
        distance.begin() + i + 1, distance.end(), length_m,
        [&](double d, double length) { return d - distance[i] < length; });
    if (j_it == distance.end()) break;  // d_k - d_i only shrinks as i grows
    const size_t j = static_cast<size_t>(j_it - distance.begin());
    const Eigen::Isometry3d T_i_j_gt = aligned.T_w_b_gt[i].inverse() * aligned.T_w_b_gt[j];
    const Eigen::Isometry3d T_i_j_est = aligned.T_w_b_est[i].inverse() * aligned.T_w_b_est[j];
    const Eigen::Isometry3d E = T_i_j_gt.inverse() * T_i_j_est;
    sum_trans_m += E.translation().norm();
    sum_rot_rad += RotationAngleRad(E.linear());
    ++result.num_pairs;
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double n = static_cast<double>(result.num_pairs);
  result.trans_pct = result.num_pairs > 0 ? sum_trans_m / n / length_m * 100.0 : nan;
  result.rot_deg_per_m = result.num_pairs > 0 ? sum_rot_rad / n * kRadToDeg / length_m : nan;
  return result;
}

}  // namespace

AteResult ComputeAte(const AssociatedTrajectory& aligned) {
  if (aligned.t_ns.empty()) throw std::invalid_argument("ATE of an empty trajectory");
  std::vector<double> position_m, rotation_deg;
  for (size_t i = 0; i < aligned.t_ns.size(); ++i) {
    const Eigen::Isometry3d& T_est = aligned.T_w_b_est[i];
    const Eigen::Isometry3d& T_gt = aligned.T_w_b_gt[i];
    position_m.push_back((T_est.translation() - T_gt.translation()).norm());
    rotation_deg.push_back(RotationAngleRad(T_gt.linear().transpose() * T_est.linear()) * kRadToDeg);
  }
  AteResult ate;
  ate.rmse_m = Rms(position_m);
  ate.mean_m = std::accumulate(position_m.begin(), position_m.end(), 0.0) /
               static_cast<double>(position_m.size());
  ate.median_m = Median(position_m);
  ate.max_m = *std::max_element(position_m.begin(), position_m.end());
  ate.rot_rmse_deg = Rms(rotation_deg);
  ate.num_poses = static_cast<int>(aligned.t_ns.size());
  ate.num_skipped = aligned.num_skipped;
  return ate;
}

std::vector<RpeResult> ComputeRpe(const AssociatedTrajectory& aligned,
                                  const std::vector<double>& lengths_m) {
  const std::vector<double> distance = PathLength(aligned.T_w_b_gt);
  std::vector<RpeResult> results;
  for (double length_m : lengths_m) {
    if (!(length_m > 0.0)) {
      std::ostringstream os;
      os << "RPE length must be > 0 m, got " << length_m;
      throw std::invalid_argument(os.str());
    }
    results.push_back(RpeAtLength(aligned, distance, length_m));
  }
  return results;
}

TrajectoryEvaluation EvaluateTrajectory(const std::vector<GroundTruthState>& estimate,
                                        const std::vector<GroundTruthState>& groundtruth,
                                        const EvaluationOptions& options) {
  const AssociatedTrajectory associated = Associate(estimate, groundtruth, options.association);
  if (associated.t_ns.empty()) {
    std::ostringstream os;
    os << "none of the " << estimate.size() << " estimate poses";
    if (!estimate.empty()) {
      os << " [" << estimate.front().t_ns << ", " << estimate.back().t_ns << "] ns";
    }
    os << " falls within the ground truth";
    if (!groundtruth.empty()) {
      os << " [" << groundtruth.front().t_ns << ", " << groundtruth.back().t_ns << "] ns";
    }
    throw std::invalid_argument(os.str());
  }
  TrajectoryEvaluation evaluation;
  evaluation.alignment = options.alignment;
  evaluation.alignment_result = Align(associated, options.alignment);
  const AssociatedTrajectory aligned = ApplyAlignment(associated, evaluation.alignment_result);
  evaluation.ate = ComputeAte(aligned);
  evaluation.rpe = ComputeRpe(aligned, options.rpe_lengths_m);
  return evaluation;
}

}  // namespace vio::tools
