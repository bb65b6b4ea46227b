// Which states and landmarks each policy marginalizes, frame by frame, on a
// scripted sequence: 13 frames of the synthetic flight whose observations are
// cut to tracks with known lifetimes,
//   B  background landmarks seen in every frame 0-12
//   V  seen in frame 0 only      X  frames 1-4
//   Y  frames 2-3                Z  frame 6 only
// The expected tables follow the paper's policies; swapping a rule (e.g.
// oldest-first removal in the MSCKF) changes them.
#include <algorithm>
#include <map>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "synthetic_window.h"
#include "vio/estimator/policy.h"
#include "vio/estimator/window.h"

namespace vio {
namespace {

constexpr int kFirst = 60;
constexpr int kFrames = 13;

using Ids = std::set<int>;

/// The scripted tracks: lifetimes [first, last] of each landmark.
struct Script {
  std::vector<int> background;
  int V = -1, X = -1, Y = -1, Z = -1;
  std::map<int, std::pair<int, int>> lifetime;
};

const test::SyntheticFlight& Flight() {
  static const test::SyntheticFlight flight(6.0, 7);
  return flight;
}

// Landmarks seen in every one of the kFrames frames: 20 background tracks
// and four with scripted lifetimes.
const Script& TheScript() {
  static const Script script = [] {
    std::map<int, int> seen;
    for (int k = 0; k < kFrames; ++k) {
      for (const StereoObservation& obs : Flight().frames()[kFirst + k].observations) ++seen[obs.landmark.value];
    }
    std::vector<int> persistent;
    for (const auto& [id, count] : seen) {
      if (count == kFrames) persistent.push_back(id);
    }
    Script s;
    EXPECT_GE(persistent.size(), 24u);
    s.V = persistent[0];
    s.X = persistent[1];
    s.Y = persistent[2];
    s.Z = persistent[3];
    s.background.assign(persistent.begin() + 4, persistent.begin() + 24);
    s.lifetime = {{s.V, {0, 0}}, {s.X, {1, 4}}, {s.Y, {2, 3}}, {s.Z, {6, 6}}};
    for (int b : s.background) s.lifetime[b] = {0, kFrames - 1};
    return s;
  }();
  return script;
}

StereoFrame ScriptedFrame(int k) {
  StereoFrame frame = Flight().frames()[kFirst + k];
  const auto& lifetime = TheScript().lifetime;
  frame.observations.erase(std::remove_if(frame.observations.begin(), frame.observations.end(),
                                          [&](const StereoObservation& obs) {
                                            auto it = lifetime.find(obs.landmark.value);
                                            return it == lifetime.end() || k < it->second.first ||
                                                   k > it->second.second;
                                          }),
                           frame.observations.end());
  return frame;
}

/// What one frame's Update did.
struct FrameRecord {
  Ids states;                  ///< in the window afterwards
  Ids landmarks;               ///< in the window afterwards
  Ids marginalized_states;
  Ids marginalized_landmarks;
  Ids held_states;             ///< held constant afterwards
  int solver_iterations = 0;
};

template <class T>
Ids ToIds(const T& ids) {
  Ids out;
  for (const auto& id : ids) out.insert(id.value);
  return out;
}

/// Runs the policy over the script: each frame a state at the ground truth
/// (5 cm off), linked by its IMU factor, then the policy's Update; the frames in
/// `lost` without observations (a tracking loss).
std::vector<FrameRecord> RunScript(const EstimatorOptions& options, const Ids& lost = {}) {
  ModelOptions model = options.model;
  Window window(model, Flight().stereo());
  std::unique_ptr<Policy> policy = MakePolicy(options);
  std::vector<FrameRecord> records;
  for (int k = 0; k < kFrames; ++k) {
    StereoFrame frame = ScriptedFrame(k);
    if (lost.count(k)) frame.observations.clear();
    Flight().AddState(window, kFirst, k, Eigen::Vector3d(0.05, 0, 0));
    window.ClearRemovals();
    const PolicyTiming timing = policy->Update(frame, StateId(k), window);
    FrameRecord record;
    for (const auto& [id, state] : window.states()) {
      record.states.insert(id.value);
      if (window.IsStateConstant(id)) record.held_states.insert(id.value);
    }
    for (const auto& [id, landmark] : window.landmarks()) record.landmarks.insert(id.value);
    record.marginalized_states = ToIds(window.removals().marginalized_states);
    record.marginalized_landmarks = ToIds(window.removals().marginalized_landmarks);
    EXPECT_TRUE(window.removals().dropped_states.empty());
    EXPECT_TRUE(window.removals().dropped_landmarks.empty());
    record.solver_iterations = timing.solver_iterations;
    records.push_back(record);
  }
  return records;
}

EstimatorOptions Options(const std::string& policy, int window_size) {
  EstimatorOptions options;
  options.policy.policy = policy;
  options.policy.window_size = window_size;
  return options;
}

Ids Background() { return Ids(TheScript().background.begin(), TheScript().background.end()); }

Ids Union(Ids a, const Ids& b) {
  a.insert(b.begin(), b.end());
  return a;
}

// MSCKF(5): beyond 5 states, x_i with i mod 3 == 2 (1-based, oldest first)
// leave, never the newest; tracks are used when they end (X at frame 5, Y at
// 4; Z, one frame long, never) and the background's views from the leaving
// states whenever it was seen from all of them; every used landmark is
// marginalized in the frame it was added.
TEST(PolicyStructure, MsckfMarginalizesEvenlySpacedStatesAndUsedTracks) {
  const Script& s = TheScript();
  const std::vector<FrameRecord> records = RunScript(Options("msckf", 5));
  const std::map<int, Ids> leaving = {{5, {1, 4}}, {7, {2, 6}}, {9, {3, 8}}, {11, {5, 10}}};
  const std::map<int, Ids> states_after = {{5, {0, 2, 3, 5}},  {6, {0, 2, 3, 5, 6}},   {7, {0, 3, 5, 7}},
                                           {8, {0, 3, 5, 7, 8}}, {9, {0, 5, 7, 9}},    {10, {0, 5, 7, 9, 10}},
                                           {11, {0, 7, 9, 11}}, {12, {0, 7, 9, 11, 12}}};
  for (int k = 0; k < kFrames; ++k) {
    SCOPED_TRACE("frame " + std::to_string(k));
    const FrameRecord& r = records[k];
    Ids expected_states;
    if (k < 5) {
      for (int i = 0; i <= k; ++i) expected_states.insert(i);
    } else {
      expected_states = states_after.at(k);
    }
    EXPECT_EQ(r.states, expected_states);
    const Ids expected_leaving = leaving.count(k) ? leaving.at(k) : Ids{};
    EXPECT_EQ(r.marginalized_states, expected_leaving);
    Ids used = leaving.count(k) ? Background() : Ids{};
    if (k == 5) used.insert(s.X);
    if (k == 4) used.insert(s.Y);
    EXPECT_EQ(r.marginalized_landmarks, used);
    EXPECT_TRUE(r.landmarks.empty());
    EXPECT_EQ(r.solver_iterations, 1);
  }
}

// SWF(4): beyond 4 states the oldest leaves; with swf_landmarks=marginalize
// every landmark it saw goes with it (seen again later, a landmark re-enters
// as new), with keep only those no other state sees.
TEST(PolicyStructure, SwfMarginalizesTheOldestStateWithItsLandmarks) {
  const Script& s = TheScript();
  for (const std::string variant : {"marginalize", "keep"}) {
    SCOPED_TRACE(variant);
    EstimatorOptions options = Options("swf", 4);
    options.policy.swf_landmarks = variant;
    const std::vector<FrameRecord> records = RunScript(options);
    const bool keep = variant == "keep";
    const std::map<int, Ids> landmarks = keep ? std::map<int, Ids>{{4, {s.V}}, {7, {s.Y}}, {8, {s.X}}, {10, {s.Z}}}
                                              : std::map<int, Ids>{{4, Union(Background(), {s.V})},
                                                                   {5, {s.X}},
                                                                   {6, {s.Y}},
                                                                   {9, Background()},
                                                                   {10, {s.Z}}};
    for (int k = 0; k < kFrames; ++k) {
      SCOPED_TRACE("frame " + std::to_string(k));
      const FrameRecord& r = records[k];
      Ids expected_states;
      for (int i = std::max(0, k - 3); i <= k; ++i) expected_states.insert(i);
      EXPECT_EQ(r.states, expected_states);
      EXPECT_EQ(r.marginalized_states, k >= 4 ? Ids{k - 4} : Ids{});
      EXPECT_EQ(r.marginalized_landmarks, landmarks.count(k) ? landmarks.at(k) : Ids{});
    }
  }
}

// fixed_lag: the MSCKF's states and tracks, Gauss-Newton to convergence.
TEST(PolicyStructure, FixedLagMarginalizesLikeTheMsckf) {
  const std::vector<FrameRecord> msckf = RunScript(Options("msckf", 5));
  const std::vector<FrameRecord> fixed_lag = RunScript(Options("fixed_lag", 5));
  for (int k = 0; k < kFrames; ++k) {
    SCOPED_TRACE("frame " + std::to_string(k));
    EXPECT_EQ(fixed_lag[k].states, msckf[k].states);
    EXPECT_EQ(fixed_lag[k].marginalized_landmarks, msckf[k].marginalized_landmarks);
    EXPECT_GE(fixed_lag[k].solver_iterations, 1);
  }
}

// EKF-SLAM (Algorithm 3): the previous state is marginalized each frame (the
// window holds the current state only) and every landmark stays: the state
// is the map seen so far. marginalize_unseen keeps only the frame's.
TEST(PolicyStructure, EkfMarginalizesThePreviousStateAndKeepsEveryLandmark) {
  const Script& s = TheScript();
  EstimatorOptions paper = Options("ekf", 1);
  paper.policy.ekf_landmarks = "keep";
  paper.policy.ekf_max_landmarks = 0;
  const std::vector<FrameRecord> records = RunScript(paper);
  Ids map;
  for (int k = 0; k < kFrames; ++k) {
    SCOPED_TRACE("frame " + std::to_string(k));
    for (const auto& [id, life] : s.lifetime) {
      if (life.first <= k && k <= life.second) map.insert(id);
    }
    EXPECT_EQ(records[k].states, Ids{k});
    EXPECT_EQ(records[k].marginalized_states, k > 0 ? Ids{k - 1} : Ids{});
    EXPECT_TRUE(records[k].marginalized_landmarks.empty());
    EXPECT_EQ(records[k].landmarks, map);
    EXPECT_EQ(records[k].solver_iterations, 1);
  }
  EstimatorOptions bounded = paper;
  bounded.policy.ekf_landmarks = "marginalize_unseen";
  const std::vector<FrameRecord> unseen = RunScript(bounded);
  size_t most_in_a_frame = 0;
  for (int k = 0; k < kFrames; ++k) {
    Ids in_frame;
    for (const auto& [id, life] : s.lifetime) {
      if (life.first <= k && k <= life.second) in_frame.insert(id);
    }
    EXPECT_EQ(unseen[k].landmarks, in_frame) << "frame " << k;
    most_in_a_frame = std::max(most_in_a_frame, in_frame.size());
  }
  // ekf_max_landmarks: the map never holds more; a landmark in it is one the frame sees.
  ASSERT_GT(most_in_a_frame, 2u);
  EstimatorOptions capped = bounded;
  capped.policy.ekf_max_landmarks = static_cast<int>(most_in_a_frame) - 1;
  const std::vector<FrameRecord> limited = RunScript(capped);
  bool full = false;
  for (int k = 0; k < kFrames; ++k) {
    SCOPED_TRACE("frame " + std::to_string(k));
    EXPECT_LE(limited[k].landmarks.size(), most_in_a_frame - 1);
    full = full || limited[k].landmarks.size() == most_in_a_frame - 1;
    for (const int id : limited[k].landmarks) EXPECT_TRUE(unseen[k].landmarks.count(id) > 0);
  }
  EXPECT_TRUE(full);
}

// The smoother(3) holds a state once 3 newer states observe landmarks: through a
// tracking loss (frames 4-7 without observations) the IMU-only states stay solved
// with the 3 tracked states before them, and are held only after 3 tracked frames
// follow (frame 10); the states are all kept.
TEST(PolicyStructure, SmootherHoldsATrackingLossOnlyAfterTrackedFramesFollowIt) {
  EstimatorOptions options = Options("smoother", 10);
  options.smoother.smoother_active_states = 3;
  const std::vector<FrameRecord> tracked = RunScript(options);
  const std::vector<FrameRecord> loss = RunScript(options, {4, 5, 6, 7});
  const std::map<int, Ids> held_after_loss = {{3, {0}},          {4, {0}},           {5, {0}},
                                              {6, {0}},          {7, {0}},           {8, {0, 1}},
                                              {9, {0, 1, 2}},    {10, {0, 1, 2, 3, 4, 5, 6, 7}},
                                              {11, {0, 1, 2, 3, 4, 5, 6, 7, 8}},
                                              {12, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9}}};
  for (int k = 0; k < kFrames; ++k) {
    SCOPED_TRACE("frame " + std::to_string(k));
    Ids every, held;
    for (int i = 0; i <= k; ++i) every.insert(i);
    for (int i = 0; i <= k - 3; ++i) held.insert(i);
    EXPECT_EQ(tracked[k].states, every);
    EXPECT_EQ(tracked[k].held_states, held);
    EXPECT_EQ(loss[k].states, every);
    EXPECT_EQ(loss[k].held_states, held_after_loss.count(k) ? held_after_loss.at(k) : Ids{});
  }
}

}  // namespace
}  // namespace vio
