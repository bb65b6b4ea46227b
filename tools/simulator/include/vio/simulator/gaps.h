#pragma once
// Frame gaps and blackouts the simulator makes on purpose, as real
// recordings have them: dropped frames (missing from cam0/cam1 data.csv, the
// IMU goes on) and blackouts (frames present but nothing to track: feature
// tracks end, rendered images are black).
#include <random>
#include <string>
#include <vector>

#include "vio/dataset/euroc_dataset.h"
#include "vio/simulator/features.h"

namespace vio::tools {

/// A span of frames without anything to track, from the first frame.
struct Blackout {
  double start_s = 0.0;     ///< [s] after the first frame
  double duration_s = 0.0;  ///< [s]
};

/// Where dropped frames go: kEven (gaps of exactly `gap_frames`, one per
/// equal block of frames) or kBurst (bursts of 1..`gap_frames` frames, placed
/// more often where the camera rotates fast, as real recordings drop them).
enum class DropPattern { kEven, kBurst };

/// "even" or "burst"; throws std::invalid_argument naming `flag` otherwise.
DropPattern ParseDropPattern(const std::string& flag, const std::string& text);

struct FrameGapOptions {
  /// Fraction of the frames removed [0, 1).
  double drop_fraction = 0.0;
  /// kEven: consecutive frames removed per gap (1 at 20 Hz: a 100 ms gap);
  /// kBurst: the longest burst.
  int gap_frames = 1;
  DropPattern pattern = DropPattern::kEven;
  std::vector<Blackout> blackouts;
};

/// "START:DURATION[,START:DURATION...]" in seconds (empty: none). Throws
/// std::invalid_argument naming `flag` on a malformed, negative or
/// overlapping entry.
std::vector<Blackout> ParseBlackouts(const std::string& flag, const std::string& text);

/// The frames without the dropped ones. kEven: round(drop_fraction * n /
/// gap_frames) gaps, one at a random place in each of as many equal blocks of
/// frames. kBurst: round(drop_fraction * n) frames in bursts of a uniform
/// 1..gap_frames frames, each starting at a frame drawn with weight 0.25 +
/// (angular rate there) / (mean angular rate), so fast rotation drops more.
/// Either way gaps never touch and the first and the last frame are kept.
/// Deterministic for `rng`, which is not used when nothing is dropped. Throws
/// std::invalid_argument naming --drop_frames / --drop_gap_frames when the
/// options are out of range or the gaps do not fit.
std::vector<FramePose> DropFrames(const std::vector<FramePose>& frames, const FrameGapOptions& options,
                                  std::mt19937_64* rng);

/// Index of the blackout holding t_ns (frames from first_ns), or -1.
int BlackoutAt(Timestamp t_ns, Timestamp first_ns, const std::vector<Blackout>& blackouts);

/// Removes the observations made during a blackout; tracks seen on both
/// sides of one end there: their later observations get new feature ids
/// (id + (blackouts ended before) * (largest id + 1)), as a front end that
/// lost them would give.
void ApplyBlackouts(const std::vector<Blackout>& blackouts, Timestamp first_ns,
                    std::vector<FeatureObservation>* observations);

}  // namespace vio::tools
