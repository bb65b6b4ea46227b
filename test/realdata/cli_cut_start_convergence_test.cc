// A start in flight converges onto the full run (docs/initialization.md, "Why
// the MSCKF's cut rows spread"): hybrid V2_01 (its first 40 s) run whole, and
// cut 20, 20.05 and 20.10 s in (one and two frames later). A cut has the full
// run's measurements from its first frame on, so once its start is forgotten
// its trajectory is the full run's: compared with SE3 alignment from 8 s after
// the cut's start on, within 2 mm. The SWF forgets its start at every offset.
// The MSCKF marginalizes every third frame (paper Algorithm 4), so a cut runs
// one of three phases of that schedule: the cut in the full run's phase
// converges as the SWF does; the others are the same filter on another schedule
// (3-4 mm apart here, against 1.4-1.5 mm), which is what the cut/full ratios
// there measure.
#include <algorithm>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/cli/run.h"
#include "vio/evaluation/trajectory_eval.h"
#include "vio/simulator/simulator.h"

namespace vio::tools {
namespace {

constexpr double kDurationS = 40.0;
constexpr double kSettleS = 8.0;        // the start's transient, excluded
constexpr double kSameRunM = 0.002;     // ATE between two runs that converged onto each other

std::string Simulate(const std::string& sequence, double from_start_s) {
  SimulatorOptions options;
  options.from_euroc_dir = sequence;
  options.from_duration_s = kDurationS - from_start_s;  // every run ends at the same frame
  options.from_start_s = from_start_s;
  options.output_dir = test::MakeTempDir("cut_start") + "/dataset";
  WriteSimulation(BuildSimulation(options), options, {});
  return options.output_dir;
}

std::vector<GroundTruthState> RunPolicy(const std::string& dataset, const std::string& policy) {
  RunRequest request;
  request.dataset_dir = dataset;
  request.output_dir = test::MakeTempDir("cut_start_run");
  request.show_progress = false;
  request.config.estimator.policy.policy = policy;
  request.config.estimator.policy.window_size = 10;
  const RunResult result = RunDataset(request);
  EXPECT_EQ(result.status, "ok") << policy << " on " << dataset;
  return ReadTumTrajectory(request.output_dir + "/trajectory.txt");
}

// ATE (SE3) of the cut run against the full run, from kSettleS after the cut's start on [m].
double DistanceAfterSettling(const std::vector<GroundTruthState>& cut, const std::vector<GroundTruthState>& full) {
  const Timestamp settled_ns = cut.front().t_ns + SecondsToNanos(kSettleS);
  std::vector<GroundTruthState> late;
  std::copy_if(cut.begin(), cut.end(), std::back_inserter(late),
               [&](const GroundTruthState& s) { return s.t_ns >= settled_ns; });
  const AssociatedTrajectory associated = Associate(late, full);
  EXPECT_GT(associated.t_ns.size(), 200u);
  return ComputeAte(ApplyAlignment(associated, Align(associated, Alignment::kSe3))).rmse_m;
}

TEST(CutStartConvergence, V2_01CutsConvergeOntoTheFullRunInTheSchedulesPhase) {
  const std::string sequence = test::EurocSequence("V2_01_easy");
  VIO_REQUIRE_DATA(sequence);
  const std::string full_dataset = Simulate(sequence, 0.0);
  std::vector<std::string> cuts;
  for (double start_s : {20.0, 20.05, 20.10}) cuts.push_back(Simulate(sequence, start_s));

  const std::vector<GroundTruthState> full_swf = RunPolicy(full_dataset, "swf");
  for (const std::string& cut : cuts) {
    EXPECT_LT(DistanceAfterSettling(RunPolicy(cut, "swf"), full_swf), kSameRunM) << "swf, " << cut;
  }
  const std::vector<GroundTruthState> full_msckf = RunPolicy(full_dataset, "msckf");
  double closest = 1e9;
  for (const std::string& cut : cuts) closest = std::min(closest, DistanceAfterSettling(RunPolicy(cut, "msckf"), full_msckf));
  EXPECT_LT(closest, kSameRunM) << "msckf: no cut converged onto the full run";
}

}  // namespace
}  // namespace vio::tools
