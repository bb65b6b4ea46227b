#include "vio/simulator/gaps.h"

#include <algorithm>
#include <cmath>
#include <sstream>
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

std::vector<FramePose> DropFrames(const std::vector<FramePose>& frames, const FrameGapOptions& options,
                                  std::mt19937_64* rng) {
  if (!(options.drop_fraction >= 0.0 && options.drop_fraction < 1.0) || options.gap_frames < 1) {
    throw std::invalid_argument("simulator: need a drop fraction in [0, 1) and at least 1 frame per gap");
  }
  const int n = static_cast<int>(frames.size());
  const int gaps = static_cast<int>(std::lround(options.drop_fraction * n / options.gap_frames));
  if (gaps == 0) return frames;
  // Blocks over frames 1 .. n-2; each holds one gap and keeps its first frame.
  const int block = (n - 2) / gaps;
  if (block < options.gap_frames + 1) {
    throw std::invalid_argument("simulator: cannot drop " + std::to_string(gaps * options.gap_frames) + " of " +
                                std::to_string(n) + " frames in gaps of " + std::to_string(options.gap_frames) +
                                " separated by kept frames");
  }
  std::vector<bool> dropped(frames.size(), false);
  for (int g = 0; g < gaps; ++g) {
    std::uniform_int_distribution<int> offset(1, block - options.gap_frames);
    const int first = 1 + g * block + offset(*rng);
    for (int k = first; k < first + options.gap_frames; ++k) dropped[k] = true;
  }
  std::vector<FramePose> kept;
  for (int k = 0; k < n; ++k) {
    if (!dropped[k]) kept.push_back(frames[k]);
  }
  return kept;
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
