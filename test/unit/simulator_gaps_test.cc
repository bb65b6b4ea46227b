// Frame gaps and blackouts of the simulator: parsing, which frames are
// dropped, and what a blackout does to feature tracks.
#include <algorithm>
#include <map>
#include <random>
#include <stdexcept>

#include <gtest/gtest.h>

#include "vio/simulator/gaps.h"

namespace vio::tools {
namespace {

std::vector<FramePose> Frames(int n, Timestamp period_ns = 50'000'000) {
  std::vector<FramePose> frames(n);
  for (int k = 0; k < n; ++k) frames[k].t_ns = 1'000'000'000 + k * period_ns;
  return frames;
}

TEST(SimGaps, ParsesBlackouts) {
  const std::vector<Blackout> b = ParseBlackouts("blackouts", "10:2,20.5:0.5");
  ASSERT_EQ(b.size(), 2u);
  EXPECT_DOUBLE_EQ(b[0].start_s, 10.0);
  EXPECT_DOUBLE_EQ(b[0].duration_s, 2.0);
  EXPECT_DOUBLE_EQ(b[1].start_s, 20.5);
  EXPECT_DOUBLE_EQ(b[1].duration_s, 0.5);
  EXPECT_TRUE(ParseBlackouts("blackouts", "").empty());
}

TEST(SimGaps, RejectsMalformedBlackoutsNamingTheFlag) {
  for (const char* text : {"10", "a:2", "10:x", "-1:2", "10:0", "10:2,11:1", "10:2:3"}) {
    try {
      ParseBlackouts("blackouts", text);
      ADD_FAILURE() << "accepted " << text;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("--blackouts"), std::string::npos) << e.what();
    }
  }
}

// 10% in single-frame gaps: 20 of 200 frames, first and last kept, no two
// dropped frames adjacent, and the same frames for the same seed.
TEST(SimGaps, DropsTheFractionInSeparatedGaps) {
  const std::vector<FramePose> frames = Frames(200);
  FrameGapOptions options;
  options.drop_fraction = 0.1;
  std::mt19937_64 rng(7), same(7);
  const std::vector<FramePose> kept = DropFrames(frames, options, &rng);
  ASSERT_EQ(kept.size(), 180u);
  EXPECT_EQ(kept.front().t_ns, frames.front().t_ns);
  EXPECT_EQ(kept.back().t_ns, frames.back().t_ns);
  for (size_t k = 1; k < kept.size(); ++k) {
    const Timestamp dt = kept[k].t_ns - kept[k - 1].t_ns;
    EXPECT_TRUE(dt == 50'000'000 || dt == 100'000'000) << dt;
  }
  const std::vector<FramePose> again = DropFrames(frames, options, &same);
  ASSERT_EQ(again.size(), kept.size());
  for (size_t k = 0; k < kept.size(); ++k) EXPECT_EQ(again[k].t_ns, kept[k].t_ns);
}

TEST(SimGaps, LongerGapsAndImpossibleRequests) {
  FrameGapOptions options;
  options.drop_fraction = 0.2;
  options.gap_frames = 4;
  std::mt19937_64 rng(1);
  const std::vector<FramePose> kept = DropFrames(Frames(200), options, &rng);
  EXPECT_EQ(kept.size(), 160u);
  Timestamp longest = 0;
  for (size_t k = 1; k < kept.size(); ++k) longest = std::max(longest, kept[k].t_ns - kept[k - 1].t_ns);
  EXPECT_EQ(longest, 250'000'000);
  options.drop_fraction = 0.9;
  EXPECT_THROW(DropFrames(Frames(200), options, &rng), std::invalid_argument);
  options.drop_fraction = 0.0;
  EXPECT_EQ(DropFrames(Frames(20), options, &rng).size(), 20u);
}

// Observations inside the blackout go; a track on both sides continues under
// a new id afterwards.
TEST(SimGaps, BlackoutEndsTracks) {
  const Timestamp first = 1'000'000'000;
  std::vector<FeatureObservation> obs;
  for (Timestamp k = 0; k < 100; ++k) {
    for (std::int64_t id : {3, 8}) obs.push_back({first + k * 50'000'000, 0, id, Eigen::Vector2d(1, 2)});
  }
  const std::vector<Blackout> blackouts = {{1.0, 2.0}};
  ApplyBlackouts(blackouts, first, &obs);
  ASSERT_EQ(obs.size(), 2u * 60u);
  for (const FeatureObservation& o : obs) {
    const double t = NanosToSeconds(o.t_ns - first);
    EXPECT_TRUE(t < 1.0 || t >= 3.0 - 1e-9) << t;
    EXPECT_EQ(BlackoutAt(o.t_ns, first, blackouts), -1);
    if (t < 1.0) {
      EXPECT_TRUE(o.feature_id == 3 || o.feature_id == 8);
    } else {
      EXPECT_TRUE(o.feature_id == 12 || o.feature_id == 17) << o.feature_id;
    }
  }
  EXPECT_TRUE(std::is_sorted(obs.begin(), obs.end(), [](const auto& a, const auto& b) {
    return std::tie(a.t_ns, a.camera, a.feature_id) < std::tie(b.t_ns, b.camera, b.feature_id);
  }));
}

// Frames turning at `fast_rad_s` in [first_fast, last_fast) and at 0.1 rad/s
// elsewhere (about the body z axis).
std::vector<FramePose> TurningFrames(int n, int first_fast, int last_fast, double fast_rad_s) {
  std::vector<FramePose> frames = Frames(n);
  double yaw = 0.0;
  for (int k = 0; k < n; ++k) {
    frames[k].T_w_b.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    yaw += 0.05 * (k >= first_fast && k < last_fast ? fast_rad_s : 0.1);
  }
  return frames;
}

// Bursts: the fraction exactly, bursts of 1..3 frames (all three lengths
// occur), separated by kept frames, first and last kept, more of them where
// the camera turns fast, the same frames for the same seed.
TEST(SimGaps, BurstsOfOneToThreeFramesMoreWhereItTurnsFast) {
  const std::vector<FramePose> frames = TurningFrames(1000, 500, 1000, 3.0);
  FrameGapOptions options;
  options.drop_fraction = 0.2;
  options.gap_frames = 3;
  options.pattern = DropPattern::kBurst;
  std::mt19937_64 rng(11), same(11);
  const std::vector<FramePose> kept = DropFrames(frames, options, &rng);
  ASSERT_EQ(kept.size(), 800u);
  EXPECT_EQ(kept.front().t_ns, frames.front().t_ns);
  EXPECT_EQ(kept.back().t_ns, frames.back().t_ns);
  std::map<Timestamp, int> burst_lengths;
  int dropped_slow = 0, dropped_fast = 0;
  for (size_t k = 1; k < kept.size(); ++k) {
    const int missing = static_cast<int>((kept[k].t_ns - kept[k - 1].t_ns) / 50'000'000) - 1;
    ASSERT_GE(missing, 0);
    ASSERT_LE(missing, 3);
    if (missing > 0) ++burst_lengths[missing];
    (kept[k].t_ns - frames.front().t_ns < 500 * 50'000'000LL ? dropped_slow : dropped_fast) += missing;
  }
  EXPECT_EQ(burst_lengths.size(), 3u);
  EXPECT_GT(dropped_fast, 3 * dropped_slow) << dropped_fast << " fast, " << dropped_slow << " slow";
  const std::vector<FramePose> again = DropFrames(frames, options, &same);
  ASSERT_EQ(again.size(), kept.size());
  for (size_t k = 0; k < kept.size(); ++k) EXPECT_EQ(again[k].t_ns, kept[k].t_ns);
}

// Out-of-range options and requests that do not fit name the flags.
TEST(SimGaps, BadDropOptionsNameTheFlag) {
  std::mt19937_64 rng(1);
  const auto message = [&](const FrameGapOptions& options) {
    try {
      DropFrames(Frames(100), options, &rng);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  FrameGapOptions options;
  options.pattern = DropPattern::kBurst;
  options.drop_fraction = 1.0;
  EXPECT_NE(message(options).find("--drop_frames"), std::string::npos) << message(options);
  options.drop_fraction = 0.1;
  options.gap_frames = 0;
  EXPECT_NE(message(options).find("--drop_gap_frames"), std::string::npos) << message(options);
  options.gap_frames = 3;
  options.drop_fraction = 0.9;  // 90 frames cannot be separated by kept frames
  EXPECT_NE(message(options).find("--drop_frames"), std::string::npos) << message(options);
  EXPECT_EQ(ParseDropPattern("drop_pattern", "burst"), DropPattern::kBurst);
  EXPECT_EQ(ParseDropPattern("drop_pattern", "even"), DropPattern::kEven);
  try {
    ParseDropPattern("drop_pattern", "bursts");
    ADD_FAILURE() << "accepted bursts";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("--drop_pattern"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace vio::tools
