#include "vio/estimator/time_offset_search.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace vio {

TimeOffsetSearch::TimeOffsetSearch(const Options& options)
    : options_(options),
      max_offset_ns_(SecondsToNanos(options.max_offset_s)),
      step_ns_(SecondsToNanos(options.step_s)) {
  if (!(options.max_offset_s > 0) || !(options.step_s > 0) || step_ns_ <= 0 || step_ns_ > max_offset_ns_) {
    throw std::invalid_argument("time offset search: the range (" + std::to_string(options.max_offset_s) +
                                " s) and the step (" + std::to_string(options.step_s) +
                                " s) must be positive, the step at most the range");
  }
  max_offset_ns_ = (max_offset_ns_ / step_ns_) * step_ns_;
  const std::size_t points = static_cast<std::size_t>(2 * (max_offset_ns_ / step_ns_) + 1);
  sum_rr_.assign(points, 0.0);
  sum_r_dt_.assign(points, Eigen::Vector3d::Zero());
}

Timestamp TimeOffsetSearch::Delta(std::size_t k) const {
  return static_cast<Timestamp>(k) * step_ns_ - max_offset_ns_;
}

void TimeOffsetSearch::AddGyro(Timestamp t_ns, const Eigen::Vector3d& gyro_rad_s) {
  if (result_) return;
  if (!gyro_.empty() && t_ns <= gyro_.back().t_ns) return;  // out of order: the estimator rejects those
  Eigen::Vector3d integral = Eigen::Vector3d::Zero();
  if (!gyro_.empty()) {
    const GyroSample& last = gyro_.back();
    integral = last.integral + 0.5 * (last.rate + gyro_rad_s) * NanosToSeconds(t_ns - last.t_ns);
  }
  gyro_.push_back({t_ns, gyro_rad_s, integral});
  ScoreReadyPairs();
  // A new pair starts at most a pair's span (well under a second) before the newest reading.
  const Timestamp keep_from = t_ns - 2 * max_offset_ns_ - SecondsToNanos(2.0);
  const Timestamp pending_from = pending_.empty() ? keep_from : pending_.front().t0_ns - max_offset_ns_;
  while (gyro_.size() > 2 && gyro_[1].t_ns <= std::min(keep_from, pending_from)) gyro_.pop_front();
}

void TimeOffsetSearch::AddPair(Timestamp t0_ns, Timestamp t1_ns, const Eigen::Vector3d& theta_camera) {
  if (result_ || t1_ns <= t0_ns) return;
  pending_.push_back({t0_ns, t1_ns, theta_camera});
  ScoreReadyPairs();
}

bool TimeOffsetSearch::Covers(const Pair& pair) const {
  return !gyro_.empty() && gyro_.front().t_ns <= pair.t0_ns - max_offset_ns_ &&
         gyro_.back().t_ns >= pair.t1_ns + max_offset_ns_;
}

void TimeOffsetSearch::ScoreReadyPairs() {
  while (!pending_.empty() && !result_) {
    const Pair pair = pending_.front();
    // Older than the gyro's history: it can never be scored.
    const bool lost = gyro_.empty() || gyro_.front().t_ns > pair.t0_ns - max_offset_ns_;
    if (!lost && !Covers(pair)) return;
    pending_.pop_front();
    if (!lost) Score(pair);
  }
}

Eigen::Vector3d TimeOffsetSearch::Integral(Timestamp t_ns) const {
  const auto after = std::upper_bound(gyro_.begin(), gyro_.end(), t_ns,
                                      [](Timestamp t, const GyroSample& g) { return t < g.t_ns; });
  if (after == gyro_.end()) return gyro_.back().integral;
  const GyroSample& a = *std::prev(after);
  const GyroSample& b = *after;
  const double dt = NanosToSeconds(b.t_ns - a.t_ns);
  const double s = NanosToSeconds(t_ns - a.t_ns) / dt;
  return a.integral + dt * (a.rate * s + (b.rate - a.rate) * (0.5 * s * s));
}

void TimeOffsetSearch::Score(const Pair& pair) {
  const double dt = NanosToSeconds(pair.t1_ns - pair.t0_ns);
  for (std::size_t k = 0; k < sum_rr_.size(); ++k) {
    const Timestamp delta = Delta(k);
    const Eigen::Vector3d r = Integral(pair.t1_ns - delta) - Integral(pair.t0_ns - delta) - pair.theta_camera;
    sum_rr_[k] += r.squaredNorm();
    sum_r_dt_[k] += r * dt;
  }
  sum_dt_dt_ += dt * dt;
  ++pairs_;
  rotation_rad_ += pair.theta_camera.norm();
  if (pairs_ >= options_.decision_pairs && rotation_rad_ >= options_.decision_rotation_rad) Decide();
}

double TimeOffsetSearch::Cost(std::size_t k) const { return sum_rr_[k] - sum_r_dt_[k].squaredNorm() / sum_dt_dt_; }

void TimeOffsetSearch::Decide() {
  std::size_t best = 0;
  for (std::size_t k = 1; k < sum_rr_.size(); ++k) {
    if (Cost(k) < Cost(best)) best = k;
  }
  Result result;
  result.pairs = pairs_;
  result.rotation_rad = rotation_rad_;
  result.delta_s = NanosToSeconds(Delta(best));
  result.at_bound = best == 0 || best + 1 == sum_rr_.size();
  double cost = Cost(best);
  const double step = NanosToSeconds(step_ns_);
  result.sigma_s = step;
  const double residual_variance = std::max(cost, 1e-300) / std::max(1, 3 * pairs_ - 4);
  if (!result.at_bound) {
    const double before = Cost(best - 1), after = Cost(best + 1);
    const double curvature = before - 2 * cost + after;  // per step^2
    if (curvature > 0) {
      const double shift = 0.5 * (before - after) / curvature;  // in steps, within [-0.5, 0.5]
      result.delta_s += shift * step;
      cost -= 0.25 * (before - after) * shift;
      // cost(delta) ~ cost + a/2 (delta - delta*)^2, a = 2 J^T J: var = sigma_r^2 (J^T J)^-1.
      const double a = curvature / (step * step);
      result.sigma_s = std::max(std::sqrt(2 * residual_variance / a), 0.1 * step);
    }
  }
  result.improvement = (Cost(sum_rr_.size() / 2) - cost) / residual_variance;
  result_ = result;
  pending_.clear();
  gyro_.clear();
}

}  // namespace vio
