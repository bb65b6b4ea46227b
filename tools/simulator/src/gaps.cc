#include "vio/simulator/gaps.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <Eigen/Geometry>
#include <stdexcept>

namespace vio::tools {
namespace {

double ParseSeconds(const std::string& flag, const std::string& item, const std::string& text) {
  std::size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(value) || value < 0.0) {
    throw std::invalid_argument("--" + flag + ": '" + item + "' is not START:DURATION in seconds (both >= 0)");
  }
  return value;
}

}  // namespace

std::vector<Blackout> ParseBlackouts(const std::string& flag, const std::string& text) {
  std::vector<Blackout> blackouts;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const std::size_t colon = item.find(':');
    if (colon == std::string::npos) {
      throw std::invalid_argument("--" + flag + ": '" + item + "' is not START:DURATION in seconds");
    }
    Blackout b{ParseSeconds(flag, item, item.substr(0, colon)), ParseSeconds(flag, item, item.substr(colon + 1))};
    if (!(b.duration_s > 0.0)) throw std::invalid_argument("--" + flag + ": '" + item + "' has no duration");
    if (!blackouts.empty() && b.start_s < blackouts.back().start_s + blackouts.back().duration_s) {
      throw std::invalid_argument("--" + flag + ": '" + item + "' starts before the previous blackout ends");
    }
    blackouts.push_back(b);
  }
  return blackouts;
}

DropPattern ParseDropPattern(const std::string& flag, const std::string& text) {
  if (text == "even") return DropPattern::kEven;
  if (text == "burst") return DropPattern::kBurst;
  throw std::invalid_argument("--" + flag + "=" + text + ": expected 'even' or 'burst'");
}

namespace {

void CheckGapOptions(const FrameGapOptions& options) {
  if (!(options.drop_fraction >= 0.0 && options.drop_fraction < 1.0)) {
    throw std::invalid_argument("--drop_frames=" + std::to_string(options.drop_fraction) +
                                ": expected a fraction in [0, 1)");
  }
  if (options.gap_frames < 1) {
    throw std::invalid_argument("--drop_gap_frames=" + std::to_string(options.gap_frames) +
                                ": expected at least 1 frame per gap");
  }
}

std::invalid_argument DoNotFit(int dropped, int n, int gap_frames) {
  return std::invalid_argument("--drop_frames, --drop_gap_frames: cannot drop " + std::to_string(dropped) + " of " +
                               std::to_string(n) + " frames in gaps of up to " + std::to_string(gap_frames) +
                               " separated by kept frames");
}

std::vector<FramePose> Kept(const std::vector<FramePose>& frames, const std::vector<bool>& dropped) {
  std::vector<FramePose> kept;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    if (!dropped[k]) kept.push_back(frames[k]);
  }
  return kept;
}

std::vector<bool> EvenGaps(int n, const FrameGapOptions& options, std::mt19937_64* rng) {
  std::vector<bool> dropped(n, false);
  const int gaps = static_cast<int>(std::lround(options.drop_fraction * n / options.gap_frames));
  if (gaps == 0) return dropped;
  // Blocks over frames 1 .. n-2; each holds one gap and keeps its first frame.
  const int block = (n - 2) / gaps;
  if (block < options.gap_frames + 1) throw DoNotFit(gaps * options.gap_frames, n, options.gap_frames);
  for (int g = 0; g < gaps; ++g) {
    std::uniform_int_distribution<int> offset(1, block - options.gap_frames);
    const int first = 1 + g * block + offset(*rng);
    for (int k = first; k < first + options.gap_frames; ++k) dropped[k] = true;
  }
  return dropped;
}

// Cumulative burst-start weights of frames 1 .. n-2: 0.25 + angular rate
// over the mean angular rate (1 each when nothing rotates).
std::vector<double> CumulativeRateWeights(const std::vector<FramePose>& frames) {
  const int n = static_cast<int>(frames.size());
  std::vector<double> rate(n, 0.0);
  double sum = 0.0;
  for (int k = 1; k + 1 < n; ++k) {
    const Eigen::AngleAxisd turn(frames[k - 1].T_w_b.linear().transpose() * frames[k + 1].T_w_b.linear());
    rate[k] = std::abs(turn.angle()) / std::max(1e-9, NanosToSeconds(frames[k + 1].t_ns - frames[k - 1].t_ns));
    sum += rate[k];
  }
  const double mean = n > 2 ? sum / (n - 2) : 0.0;
  std::vector<double> cumulative(n, 0.0);
  for (int k = 1; k < n; ++k) {
    const double w = k + 1 < n ? (mean > 0.0 ? 0.25 + rate[k] / mean : 1.0) : 0.0;
    cumulative[k] = cumulative[k - 1] + w;
  }
  return cumulative;
}

std::vector<bool> BurstGaps(const std::vector<FramePose>& frames, const FrameGapOptions& options,
                            std::mt19937_64* rng) {
  const int n = static_cast<int>(frames.size());
  std::vector<bool> dropped(n, false);
  const int target = static_cast<int>(std::lround(options.drop_fraction * n));
  if (target == 0) return dropped;
  if (n < 3) throw DoNotFit(target, n, options.gap_frames);
  const std::vector<double> cumulative = CumulativeRateWeights(frames);
  std::uniform_real_distribution<double> pick(0.0, cumulative.back());
  std::uniform_int_distribution<int> length(1, options.gap_frames);
  int count = 0;
  for (std::int64_t attempt = 0; count < target; ++attempt) {
    if (attempt > 1000 * static_cast<std::int64_t>(n)) throw DoNotFit(target, n, options.gap_frames);
    const int first = static_cast<int>(std::upper_bound(cumulative.begin(), cumulative.end(), pick(*rng)) -
                                       cumulative.begin());
    const int last = first + std::min(length(*rng), target - count) - 1;  // inclusive
    if (first < 1 || last > n - 2) continue;
    bool free = true;
    for (int k = first - 1; k <= last + 1; ++k) free = free && !dropped[k];
    if (!free) continue;
    for (int k = first; k <= last; ++k) dropped[k] = true;
    count += last - first + 1;
  }
  return dropped;
}

}  // namespace

std::vector<FramePose> DropFrames(const std::vector<FramePose>& frames, const FrameGapOptions& options,
                                  std::mt19937_64* rng) {
  CheckGapOptions(options);
  const int n = static_cast<int>(frames.size());
  const std::vector<bool> dropped =
      options.pattern == DropPattern::kBurst ? BurstGaps(frames, options, rng) : EvenGaps(n, options, rng);
  return Kept(frames, dropped);
}

int BlackoutAt(Timestamp t_ns, Timestamp first_ns, const std::vector<Blackout>& blackouts) {
  const double t_s = NanosToSeconds(t_ns - first_ns);
  for (std::size_t i = 0; i < blackouts.size(); ++i) {
    if (t_s >= blackouts[i].start_s && t_s < blackouts[i].start_s + blackouts[i].duration_s) {
      return static_cast<int>(i);
    }
  }
  return -1;
}

void ApplyBlackouts(const std::vector<Blackout>& blackouts, Timestamp first_ns,
                    std::vector<FeatureObservation>* observations) {
  if (blackouts.empty() || observations->empty()) return;
  std::int64_t stride = 0;
  for (const FeatureObservation& o : *observations) stride = std::max(stride, o.feature_id + 1);
  std::vector<FeatureObservation> kept;
  for (FeatureObservation o : *observations) {
    if (BlackoutAt(o.t_ns, first_ns, blackouts) >= 0) continue;
    const double t_s = NanosToSeconds(o.t_ns - first_ns);
    const auto ended = std::count_if(blackouts.begin(), blackouts.end(),
                                     [&](const Blackout& b) { return b.start_s + b.duration_s <= t_s; });
    o.feature_id += ended * stride;
    kept.push_back(o);
  }
  *observations = std::move(kept);
}

}  // namespace vio::tools
