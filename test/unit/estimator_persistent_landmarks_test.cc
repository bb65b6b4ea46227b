// Long-lived landmarks (persistent_landmarks.h) on a scripted sequence: 18
// frames of the synthetic flight whose observations are cut to
//   B  background landmarks seen in every frame 0-17
//   R  returning landmarks seen in frames 0-5, unseen 6-11, seen again 12-17
// SWF(4) and MSCKF(5) with persistent_landmarks: R is promoted when its first
// observing state leaves, stays a parameter (in the prior) while unseen, its
// observations re-attach to it at frame 12, and it is marginalized when not
// seen for persistent_retire_s or when the budget is exceeded.
#include "vio/estimator/persistent_landmarks.h"

#include <algorithm>
#include <cstring>
#include <iterator>
#include <map>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "synthetic_window.h"
#include "vio/estimator/msckf_policy.h"
#include "vio/estimator/swf_policy.h"
#include "vio/estimator/window.h"
#include "vio/estimator/window_covariance.h"

namespace vio {
namespace {

constexpr int kFirst = 60;
constexpr int kFrames = 18;
constexpr int kGoneFrom = 6;   // R unseen in frames [kGoneFrom, kBackAt)
constexpr int kBackAt = 12;

using Ids = std::set<int>;

const test::SyntheticFlight& Flight() {
  static const test::SyntheticFlight flight(6.0, 7);
  return flight;
}

struct Script {
  Ids background;  // B
  Ids returning;   // R
};

// Landmarks seen in all kFrames frames: the first 10 return, the next 20 are the background.
const Script& TheScript() {
  static const Script script = [] {
    std::map<int, int> seen;
    for (int k = 0; k < kFrames; ++k) {
      for (const StereoObservation& obs : Flight().frames()[kFirst + k].observations) ++seen[obs.landmark.value];
    }
    std::vector<int> always;
    for (const auto& [id, count] : seen) {
      if (count == kFrames) always.push_back(id);
    }
    EXPECT_GE(always.size(), 30u);
    Script s;
    s.returning.insert(always.begin(), always.begin() + 10);
    s.background.insert(always.begin() + 10, always.begin() + 30);
    return s;
  }();
  return script;
}

StereoFrame ScriptedFrame(int k, bool returns) {
  StereoFrame frame = Flight().frames()[kFirst + k];
  const Script& s = TheScript();
  const bool r_visible = k < kGoneFrom || (returns && k >= kBackAt);
  frame.observations.erase(std::remove_if(frame.observations.begin(), frame.observations.end(),
                                          [&](const StereoObservation& obs) {
                                            const int id = static_cast<int>(obs.landmark.value);
                                            return !(s.background.count(id) || (r_visible && s.returning.count(id)));
                                          }),
                           frame.observations.end());
  return frame;
}

/// What one frame's Update left.
struct FrameRecord {
  Ids landmarks;               ///< in the window afterwards
  Ids marginalized_landmarks;
  Ids kept;                    ///< long-lived (the policy's bookkeeping)
  std::map<int, Ids> observed_from;  ///< landmark -> states observing it in the window
  double position_variance = 0;      ///< trace of the newest state's position covariance [m^2]
  std::vector<double> newest_pose;   ///< the newest state's pose block, bit for bit
};

template <class T>
Ids ToIds(const T& ids) {
  Ids out;
  for (const auto& id : ids) out.insert(static_cast<int>(id.value));
  return out;
}

template <class PolicyType>
std::vector<FrameRecord> RunScript(const EstimatorOptions& options, bool returns, PolicyType& policy) {
  Window window(options.model, Flight().stereo());
  std::vector<FrameRecord> records;
  for (int k = 0; k < kFrames; ++k) {
    const StereoFrame frame = ScriptedFrame(k, returns);
    Flight().AddState(window, kFirst, k, Eigen::Vector3d(0.05, 0, 0));
    window.ClearRemovals();
    policy.Update(frame, StateId(k), window);
    FrameRecord r;
    r.marginalized_landmarks = ToIds(window.removals().marginalized_landmarks);
    for (const auto& [id, landmark] : window.landmarks()) {
      r.landmarks.insert(static_cast<int>(id.value));
      r.observed_from[static_cast<int>(id.value)] = ToIds(landmark.observed_from);
      if (policy.persistent().IsKept(id)) r.kept.insert(static_cast<int>(id.value));
    }
    const std::optional<StateCovariance> covariance = NewestStateCovariance(window);
    EXPECT_TRUE(covariance.has_value()) << "frame " << k;
    if (covariance) r.position_variance = covariance->covariance.topLeftCorner<3, 3>().trace();
    const State& newest = window.state(StateId(k));
    r.newest_pose.assign(newest.pose, newest.pose + 7);
    records.push_back(r);
  }
  return records;
}

EstimatorOptions Options(const std::string& policy, int window_size, int budget, double retire_s) {
  EstimatorOptions options;
  options.policy.policy = policy;
  options.policy.window_size = window_size;
  options.persistent.persistent_landmarks = budget;
  options.persistent.persistent_min_track = 3;
  options.persistent.persistent_retire_s = retire_s;
  return options;
}

std::vector<FrameRecord> RunSwf(const EstimatorOptions& options, bool returns) {
  SwfPolicy policy(options);
  return RunScript(options, returns, policy);
}

std::vector<FrameRecord> RunMsckf(const EstimatorOptions& options, bool returns) {
  MsckfPolicy policy(options, options.msckf.msckf_gn_steps);
  return RunScript(options, returns, policy);
}

bool Contains(const Ids& set, const Ids& subset) {
  return std::includes(set.begin(), set.end(), subset.begin(), subset.end());
}

Ids Intersection(const Ids& a, const Ids& b) {
  Ids out;
  std::set_intersection(a.begin(), a.end(), b.begin(), b.end(), std::inserter(out, out.begin()));
  return out;
}

// The bookkeeping alone: promotion needs persistent_min_track observations,
// the budget keeps the most useful (most observations, then newest), and a
// landmark unseen for persistent_retire_s retires.
TEST(PersistentLandmarks, PromotesRanksAndRetires) {
  PersistentOptions options;
  options.persistent_landmarks = 2;
  options.persistent_min_track = 3;
  options.persistent_retire_s = 1.0;
  PersistentLandmarks kept(options);
  const Timestamp t0 = SecondsToNanos(100.0);
  PersistentDecision d = kept.Decide(t0, {{LandmarkId(1), 2, t0}, {LandmarkId(2), 3, t0}, {LandmarkId(3), 5, t0}});
  EXPECT_EQ(ToIds(d.promoted), (Ids{2, 3}));  // 1 is too short
  EXPECT_TRUE(d.retired.empty());
  // 4 (4 observations) beats 2 (3): 2 retires for the budget.
  d = kept.Decide(t0, {{LandmarkId(4), 4, t0}});
  EXPECT_EQ(ToIds(d.promoted), Ids{4});
  EXPECT_EQ(ToIds(d.retired), Ids{2});
  EXPECT_EQ(kept.counts().retired_budget, 1);
  // 3 is re-observed; 4 is not and retires after 1 s; then 5 finds room.
  StereoFrame frame{t0 + SecondsToNanos(0.9), {{LandmarkId(3), Eigen::Vector3d::Zero()}}};
  kept.Observe(frame);
  d = kept.Decide(t0 + SecondsToNanos(1.5), {{LandmarkId(5), 3, t0 + SecondsToNanos(1.5)}});
  EXPECT_EQ(ToIds(d.retired), Ids{4});
  EXPECT_EQ(ToIds(d.promoted), Ids{5});
  EXPECT_TRUE(kept.IsKept(LandmarkId(3)));
  EXPECT_EQ(kept.counts().retired_unseen, 1);
  EXPECT_EQ(kept.size(), 2);
}

// SWF(4), budget 100, no retirement within the script: R and B are promoted
// when state 0 leaves (frame 4), R stays in the window, unobserved, in frames
// 8-11 (its last observing state left), and at frame 12 its observation
// re-attaches to the same variable; it is never marginalized.
TEST(PersistentLandmarks, SwfKeepsAndReattachesAReturningLandmark) {
  const Script& s = TheScript();
  const std::vector<FrameRecord> records = RunSwf(Options("swf", 4, 100, 10.0), true);
  for (int k = 0; k < kFrames; ++k) {
    SCOPED_TRACE("frame " + std::to_string(k));
    const FrameRecord& r = records[k];
    EXPECT_TRUE(Intersection(r.marginalized_landmarks, s.returning).empty());
    EXPECT_TRUE(Intersection(r.marginalized_landmarks, s.background).empty());
    EXPECT_TRUE(Contains(r.landmarks, s.returning));
    if (k >= 4) {
      EXPECT_TRUE(Contains(r.kept, s.returning));
    }
    for (int id : s.returning) {
      const Ids& from = r.observed_from.at(id);
      if (k >= kGoneFrom + 3 && k < kBackAt) {
        EXPECT_TRUE(from.empty()) << id;  // held by the prior only
      }
      if (k >= kBackAt) {
        EXPECT_TRUE(from.count(k)) << id;  // re-attached
        EXPECT_EQ(from.size(), static_cast<size_t>(std::min(k - kBackAt + 1, 4))) << id;
      }
    }
  }
}

// The re-observation brings information: the newest pose's position
// covariance after the return is smaller than in the same run without the
// return. (The pose error is not compared: every state starts 5 cm off, as
// does the first state's prior, so it is dominated by that shift.)
TEST(PersistentLandmarks, ReobservationReducesThePoseCovariance) {
  for (const std::string policy : {"swf", "msckf"}) {
    SCOPED_TRACE(policy);
    const EstimatorOptions options = Options(policy, policy == "swf" ? 4 : 5, 100, 10.0);
    const auto run = policy == "swf" ? RunSwf : RunMsckf;
    const std::vector<FrameRecord> back = run(options, true);
    const std::vector<FrameRecord> gone = run(options, false);
    for (int k = kBackAt; k < kFrames; ++k) {
      SCOPED_TRACE("frame " + std::to_string(k));
      // Measured: 0.47-0.63 of the variance without the return.
      EXPECT_LT(back[k].position_variance, 0.8 * gone[k].position_variance);
    }
  }
}

// MSCKF(5): tracks are used (triangulated) and kept instead of marginalized;
// a kept landmark's observations go to the window directly (re-attachment).
TEST(PersistentLandmarks, MsckfKeepsUsedTracksAndReattaches) {
  const Script& s = TheScript();
  const std::vector<FrameRecord> records = RunMsckf(Options("msckf", 5, 100, 10.0), true);
  for (int k = 0; k < kFrames; ++k) {
    SCOPED_TRACE("frame " + std::to_string(k));
    const FrameRecord& r = records[k];
    EXPECT_TRUE(Intersection(r.marginalized_landmarks, s.returning).empty());
    // R's track ends at frame 6 and is used then: kept from then on.
    if (k >= kGoneFrom) {
      EXPECT_TRUE(Contains(r.kept, s.returning));
    }
    if (k >= kBackAt) {
      for (int id : s.returning) EXPECT_TRUE(r.observed_from.at(id).count(k)) << id;
    }
    EXPECT_TRUE(Contains(r.landmarks, r.kept));
  }
}

// Retirement: with persistent_retire_s = 0.2 s (4 frames at 20 Hz), R
// (last seen at frame 5) is marginalized once more than 0.2 s passed, and
// re-enters as a new landmark at frame 12 (observed from that state only).
TEST(PersistentLandmarks, UnseenLandmarksRetire) {
  const Script& s = TheScript();
  const std::vector<FrameRecord> records = RunSwf(Options("swf", 4, 100, 0.2), true);
  const Timestamp last_seen = Flight().frames()[kFirst + kGoneFrom - 1].t_ns;
  int retired_at = -1;
  for (int k = 0; k < kFrames; ++k) {
    if (Contains(records[k].marginalized_landmarks, s.returning)) retired_at = k;
  }
  ASSERT_GE(retired_at, 0);
  const Timestamp t = Flight().frames()[kFirst + retired_at].t_ns;
  const Timestamp before = Flight().frames()[kFirst + retired_at - 1].t_ns;
  EXPECT_GT(t - last_seen, SecondsToNanos(0.2));
  EXPECT_LE(before - last_seen, SecondsToNanos(0.2));
  for (int k = retired_at; k < kBackAt; ++k) EXPECT_TRUE(Intersection(records[k].landmarks, s.returning).empty()) << k;
  for (int id : s.returning) EXPECT_EQ(records[kBackAt].observed_from.at(id), Ids{kBackAt}) << id;
}

// The budget holds every frame, for both policies, and fills up.
TEST(PersistentLandmarks, BudgetIsRespected) {
  for (const std::string policy : {"swf", "msckf"}) {
    SCOPED_TRACE(policy);
    const EstimatorOptions options = Options(policy, policy == "swf" ? 4 : 5, 7, 10.0);
    const std::vector<FrameRecord> records = policy == "swf" ? RunSwf(options, true) : RunMsckf(options, true);
    for (int k = 0; k < kFrames; ++k) {
      EXPECT_LE(records[k].kept.size(), 7u) << k;
      // Landmarks no state in the window observes are kept ones.
      int unobserved = 0;
      for (const auto& [id, from] : records[k].observed_from) unobserved += from.empty();
      EXPECT_LE(unobserved, 7) << k;
    }
    EXPECT_EQ(records[kFrames - 1].kept.size(), 7u);
  }
}

// Off (persistent_landmarks 0, the default): the other two options change
// nothing, bit for bit, and no landmark outlives its states.
TEST(PersistentLandmarks, OffIsBitIdentical) {
  for (const std::string policy : {"swf", "msckf"}) {
    SCOPED_TRACE(policy);
    const int window = policy == "swf" ? 4 : 5;
    EstimatorOptions defaults;
    defaults.policy.policy = policy;
    defaults.policy.window_size = window;
    const EstimatorOptions other = Options(policy, window, 0, 0.01);
    const auto run = policy == "swf" ? RunSwf : RunMsckf;
    const std::vector<FrameRecord> a = run(defaults, true);
    const std::vector<FrameRecord> b = run(other, true);
    for (int k = 0; k < kFrames; ++k) {
      EXPECT_EQ(std::memcmp(a[k].newest_pose.data(), b[k].newest_pose.data(), 7 * sizeof(double)), 0) << k;
      EXPECT_EQ(a[k].marginalized_landmarks, b[k].marginalized_landmarks) << k;
      EXPECT_TRUE(b[k].kept.empty());
      for (const auto& [id, from] : b[k].observed_from) EXPECT_FALSE(from.empty()) << k << " " << id;
    }
  }
}

}  // namespace
}  // namespace vio
