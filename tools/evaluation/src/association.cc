// Association of estimate stamps with ground truth: interpolation on SE(3)
// as linear position and slerp rotation between the bracketing samples.
#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "vio/evaluation/trajectory_eval.h"

namespace vio::tools {
namespace {

Eigen::Isometry3d ToIsometry(const Eigen::Vector3d& p_w_b, const Eigen::Quaterniond& q_w_b) {
  Eigen::Isometry3d T_w_b = Eigen::Isometry3d::Identity();
  T_w_b.linear() = q_w_b.normalized().toRotationMatrix();
  T_w_b.translation() = p_w_b;
  return T_w_b;
}

void CheckIncreasing(const std::vector<GroundTruthState>& poses, const std::string& what) {
  for (size_t i = 1; i < poses.size(); ++i) {
    if (poses[i].t_ns <= poses[i - 1].t_ns) {
      std::ostringstream os;
      os << what << " stamps are not strictly increasing: pose " << i << " at " << poses[i].t_ns
         << " ns follows " << poses[i - 1].t_ns << " ns";
      throw std::invalid_argument(os.str());
    }
  }
}

// With a (t0) and b (t1) bracketing t, alpha = (t - t0) / (t1 - t0):
//   p(t) = (1 - alpha) p_a + alpha p_b,   q(t) = slerp(q_a, q_b, alpha).
Eigen::Isometry3d Interpolate(const GroundTruthState& a, const GroundTruthState& b, Timestamp t_ns) {
  const double alpha =
      static_cast<double>(t_ns - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
  const Eigen::Vector3d p_w_b = (1.0 - alpha) * a.p_w_b + alpha * b.p_w_b;
  const Eigen::Quaterniond q_w_b = a.q_w_b.normalized().slerp(alpha, b.q_w_b.normalized());
  return ToIsometry(p_w_b, q_w_b);
}

// Ground truth at t_ns, or false when t_ns is outside the span (beyond the
// tolerance) or inside a gap longer than max_gap_ns.
bool GroundTruthAt(const std::vector<GroundTruthState>& gt, Timestamp t_ns,
                   const AssociationOptions& options, Eigen::Isometry3d* T_w_b_gt) {
  if (t_ns <= gt.front().t_ns) {
    if (gt.front().t_ns - t_ns > options.tolerance_ns) return false;
    *T_w_b_gt = ToIsometry(gt.front().p_w_b, gt.front().q_w_b);
    return true;
  }
  if (t_ns >= gt.back().t_ns) {
    if (t_ns - gt.back().t_ns > options.tolerance_ns) return false;
    *T_w_b_gt = ToIsometry(gt.back().p_w_b, gt.back().q_w_b);
    return true;
  }
  // First sample strictly after t_ns; its predecessor is at or before t_ns.
  const auto after = std::upper_bound(
      gt.begin(), gt.end(), t_ns, [](Timestamp t, const GroundTruthState& s) { return t < s.t_ns; });
  const GroundTruthState& b = *after;
  const GroundTruthState& a = *(after - 1);
  if (b.t_ns - a.t_ns > options.max_gap_ns) return false;
  *T_w_b_gt = Interpolate(a, b, t_ns);
  return true;
}

// The gap bound: as given, or kAutoGapPeriods median sample intervals of the
// ground truth.
Timestamp MaxGapNs(const std::vector<GroundTruthState>& gt, const AssociationOptions& options) {
  if (options.max_gap_ns > 0 || gt.size() < 2) return options.max_gap_ns;
  std::vector<Timestamp> intervals;
  intervals.reserve(gt.size() - 1);
  for (size_t i = 1; i < gt.size(); ++i) intervals.push_back(gt[i].t_ns - gt[i - 1].t_ns);
  std::nth_element(intervals.begin(), intervals.begin() + intervals.size() / 2, intervals.end());
  return kAutoGapPeriods * intervals[intervals.size() / 2];
}

}  // namespace

AssociatedTrajectory Associate(const std::vector<GroundTruthState>& estimate,
                               const std::vector<GroundTruthState>& groundtruth,
                               const AssociationOptions& options) {
  CheckIncreasing(estimate, "estimate");
  CheckIncreasing(groundtruth, "ground truth");
  AssociationOptions resolved = options;
  resolved.max_gap_ns = MaxGapNs(groundtruth, options);
  AssociatedTrajectory out;
  for (const GroundTruthState& est : estimate) {
    Eigen::Isometry3d T_w_b_gt;
    if (groundtruth.empty() || !GroundTruthAt(groundtruth, est.t_ns, resolved, &T_w_b_gt)) {
      ++out.num_skipped;
      continue;
    }
    out.t_ns.push_back(est.t_ns);
    out.T_w_b_est.push_back(ToIsometry(est.p_w_b, est.q_w_b));
    out.T_w_b_gt.push_back(T_w_b_gt);
  }
  return out;
}

}  // namespace vio::tools
