// `vio run` end to end on a short synthetic dataset the simulator makes:
// the SWF tracks the ground truth, and the same command twice, or with
// another output folder and environment, writes byte-identical trajectories.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/cli/run.h"
#include "vio/dataset/frame_source.h"
#include "vio/simulator/simulator.h"

namespace vio::tools {
namespace {

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

const std::string& SyntheticDataset() {
  static const std::string dir = [] {
    SimulatorOptions options;
    options.output_dir = test::MakeTempDir("run_synthetic") + "/dataset";
    options.duration_s = 15.0;
    options.seed = 3;
    Simulate(options);
    return options.output_dir;
  }();
  return dir;
}

// The same flight with 10% of the frames dropped (100 ms gaps) and a 2 s
// blackout 7 s after the first frame (4 s into the motion).
const std::string& GappedSyntheticDataset() {
  static const std::string dir = [] {
    SimulatorOptions options;
    options.output_dir = test::MakeTempDir("run_synthetic_gaps") + "/dataset";
    options.duration_s = 15.0;
    options.seed = 3;
    options.gaps.drop_fraction = 0.1;
    options.gaps.blackouts = {{7.0, 2.0}};
    Simulate(options);
    return options.output_dir;
  }();
  return dir;
}

RunResult RunOnSynthetic(const std::string& output_dir, const std::string& policy = "swf") {
  RunRequest request;
  request.dataset_dir = SyntheticDataset();
  request.output_dir = output_dir;
  request.show_progress = false;
  request.config.estimator.policy.policy = policy;
  return RunDataset(request);
}

// Every policy runs the whole flight and stays close to the ground truth.
class EveryPolicy : public ::testing::TestWithParam<std::pair<std::string, double>> {};

TEST_P(EveryPolicy, TracksTheSyntheticFlight) {
  const auto& [policy, ate_bound_m] = GetParam();
  const RunResult result = RunOnSynthetic(test::MakeTempDir("run_policy_" + policy), policy);
  EXPECT_EQ(result.status, "ok") << policy;
  // Every frame after static initialization (IMU stillness over 1 s: 20 frames).
  EXPECT_EQ(result.frames_estimated + result.health.frames_waiting_init, result.frames) << policy;
  EXPECT_LE(result.health.frames_waiting_init, 21) << policy;
  ASSERT_TRUE(result.evaluation.has_value());
  EXPECT_LT(result.evaluation->ate.rmse_m, ate_bound_m) << policy;
}

INSTANTIATE_TEST_SUITE_P(Policies, EveryPolicy,
                         ::testing::Values(std::make_pair("msckf", 0.05), std::make_pair("fixed_lag", 0.05),
                                           std::make_pair("keyframe", 0.05)),
                         [](const auto& info) { return info.param.first; });

// Dropped frames and a blackout longer than the window: every policy
// propagates through it on the IMU, counts it and regains tracking (iekf is
// ekf with more iterations: left out, it takes a minute and a half here).
class EveryPolicyThroughGaps : public ::testing::TestWithParam<std::pair<std::string, double>> {};

TEST_P(EveryPolicyThroughGaps, SurvivesDroppedFramesAndABlackout) {
  const auto& [policy, ate_bound_m] = GetParam();
  RunRequest request;
  request.dataset_dir = GappedSyntheticDataset();
  request.output_dir = test::MakeTempDir("run_gaps_" + policy);
  request.show_progress = false;
  request.config.estimator.policy.policy = policy;
  // ekf: the bounded variant (the paper's keep-every-landmark EKF-SLAM takes
  // minutes here; it runs in the slow suite).
  request.config.estimator.policy.ekf_landmarks = "marginalize_unseen";
  const RunResult result = RunDataset(request);
  EXPECT_EQ(result.status, "ok") << policy;
  EXPECT_EQ(result.frames_estimated + result.health.frames_waiting_init, result.frames) << policy;
  EXPECT_LE(result.health.frames_waiting_init, 21) << policy;
  EXPECT_GE(result.frame_gaps, 20) << policy;
  EXPECT_NEAR(result.longest_frame_gap_s, 0.1, 1e-6) << policy;
  EXPECT_EQ(result.tracking.losses, 1) << policy;
  EXPECT_EQ(result.tracking.losses_beyond_window, 1) << policy;
  EXPECT_GE(result.tracking.untracked_frames, 30) << policy;
  EXPECT_LE(result.tracking.untracked_frames, 40) << policy;
  EXPECT_NEAR(result.tracking.longest_loss_s, 2.0, 0.15) << policy;
  ASSERT_TRUE(result.evaluation.has_value());
  EXPECT_LT(result.evaluation->ate.rmse_m, ate_bound_m) << policy;
  ::testing::Test::RecordProperty(policy + "_ate_rmse_m", std::to_string(result.evaluation->ate.rmse_m));
}

INSTANTIATE_TEST_SUITE_P(Policies, EveryPolicyThroughGaps,
                         ::testing::Values(std::make_pair("swf", 0.1), std::make_pair("msckf", 0.1),
                                           std::make_pair("fixed_lag", 0.1), std::make_pair("keyframe", 0.1),
                                           std::make_pair("ekf", 0.1), std::make_pair("batch", 0.1)),
                         [](const auto& info) { return info.param.first; });

// The MSCKF's other use of tracks seen from leaving states (whole tracks,
// restarted) runs the flight as well.
TEST(RunSynthetic, MsckfWithWholeTracksTracksTheSyntheticFlight) {
  RunRequest request;
  request.dataset_dir = SyntheticDataset();
  request.output_dir = test::MakeTempDir("run_msckf_whole_track");
  request.show_progress = false;
  request.config.estimator.policy.policy = "msckf";
  request.config.estimator.msckf.msckf_leaving_update = "whole_track";
  const RunResult result = RunDataset(request);
  EXPECT_EQ(result.status, "ok");
  ASSERT_TRUE(result.evaluation.has_value());
  EXPECT_LE(result.evaluation->ate.rmse_m, 0.05);
}

TEST(RunSynthetic, SwfTracksTheSyntheticFlight) {
  const std::string out = test::MakeTempDir("run_synthetic_out");
  const RunResult result = RunOnSynthetic(out);
  EXPECT_EQ(result.status, "ok");
  // Every frame after static initialization (IMU stillness over 1 s: 20 frames).
  EXPECT_EQ(result.frames_estimated + result.health.frames_waiting_init, result.frames);
  EXPECT_LE(result.health.frames_waiting_init, 21);
  ASSERT_TRUE(result.evaluation.has_value());
  EXPECT_LT(result.evaluation->ate.rmse_m, 0.03);
  EXPECT_LT(result.evaluation->ate.rot_rmse_deg, 1.0);
  for (const char* file : {"trajectory.txt", "summary.json", "timing.csv", "config.yaml"}) {
    EXPECT_TRUE(std::filesystem::exists(out + "/" + file)) << file;
  }
}

// The synthetic flight with only `keep` features per frame for 2 s, 6 s after
// the first frame: the rows of every other feature id of those frames go.
std::string SparseStretchDataset(int keep) {
  const std::string dir = test::MakeTempDir("run_synthetic_sparse") + "/dataset";
  std::filesystem::copy(SyntheticDataset(), dir, std::filesystem::copy_options::recursive);
  const std::string csv = dir + "/mav0/features0/data.csv";
  std::istringstream in(ReadFile(csv));
  std::ostringstream out;
  std::string line;
  long long first_ns = -1;
  std::map<long long, std::set<long long>> kept_ids;  // per frame
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') {
      out << line << "\n";
      continue;
    }
    std::istringstream row(line);
    std::string t, camera, id;
    std::getline(row, t, ',');
    std::getline(row, camera, ',');
    std::getline(row, id, ',');
    const long long t_ns = std::stoll(t);
    if (first_ns < 0) first_ns = t_ns;
    const double since_s = static_cast<double>(t_ns - first_ns) * 1e-9;
    std::set<long long>& ids = kept_ids[t_ns];
    if (since_s >= 6.0 && since_s < 8.0 && ids.count(std::stoll(id)) == 0) {
      if (camera != "0" || static_cast<int>(ids.size()) >= keep) continue;
      ids.insert(std::stoll(id));
    }
    out << line << "\n";
  }
  std::ofstream(csv, std::ios::binary) << out.str();
  return dir;
}

// With min_frame_features 1, frames with a few stereo observations are used,
// not taken as tracking loss: through 2 s of four features per frame the SWF
// stays closer to the ground truth than with the default 10, which takes them
// as lost and dead-reckons on the IMU.
TEST(RunSynthetic, FewFeaturesPerFrameAreUsedNotLost) {
  const std::string dataset = SparseStretchDataset(4);
  const auto run = [&](int min_frame_features) {
    RunRequest request;
    request.dataset_dir = dataset;
    request.output_dir = test::MakeTempDir("run_sparse_" + std::to_string(min_frame_features));
    request.show_progress = false;
    request.config.estimator.policy.min_frame_features = min_frame_features;
    return RunDataset(request);
  };
  const RunResult used = run(1);
  const RunResult lost = run(PolicyOptions().min_frame_features);
  EXPECT_EQ(used.status, "ok");
  EXPECT_EQ(used.tracking.losses, 0);
  EXPECT_EQ(lost.tracking.losses, 1);
  EXPECT_GE(lost.tracking.untracked_frames, 35);
  ASSERT_TRUE(used.evaluation.has_value() && lost.evaluation.has_value());
  EXPECT_LT(used.evaluation->ate.rmse_m, lost.evaluation->ate.rmse_m);
  ::testing::Test::RecordProperty("ate_used_m", std::to_string(used.evaluation->ate.rmse_m));
  ::testing::Test::RecordProperty("ate_lost_m", std::to_string(lost.evaluation->ate.rmse_m));
}

// --trajectory=smoothed: every frame refined after the online pass. Most
// frames, the newest one included, differ from the online estimate, and both
// track the flight.
TEST(RunSynthetic, SmoothedTrajectoryRefinesEveryFrame) {
  const std::string online_dir = test::MakeTempDir("run_online");
  const std::string smoothed_dir = test::MakeTempDir("run_smoothed");
  const RunResult online = RunOnSynthetic(online_dir);
  RunRequest request;
  request.dataset_dir = SyntheticDataset();
  request.output_dir = smoothed_dir;
  request.show_progress = false;
  request.trajectory = "smoothed";
  const RunResult smoothed = RunDataset(request);
  ASSERT_EQ(smoothed.status, "ok");
  ASSERT_TRUE(smoothed.evaluation.has_value() && online.evaluation.has_value());
  EXPECT_LT(smoothed.evaluation->ate.rmse_m, 0.03);
  EXPECT_NE(smoothed.evaluation->ate.rmse_m, online.evaluation->ate.rmse_m);
  const auto rows = [](const std::string& dir) {
    std::vector<std::string> lines;
    std::istringstream in(ReadFile(dir + "/trajectory.txt"));
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
  };
  const std::vector<std::string> a = rows(online_dir), b = rows(smoothed_dir);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 100u);
  EXPECT_NE(a.back(), b.back()) << "the newest state is refined too";
  int differing = 0;
  for (size_t k = 0; k < a.size(); ++k) differing += a[k] != b[k];
  EXPECT_GT(differing, static_cast<int>(a.size()) / 2);
  EXPECT_NE(ReadFile(smoothed_dir + "/summary.json").find("\"trajectory\": \"smoothed\""), std::string::npos);
}

TEST(RunSynthetic, SmoothedTrajectoryWithCovarianceIsAClearError) {
  RunRequest request;
  request.dataset_dir = SyntheticDataset();
  request.output_dir = test::MakeTempDir("run_smoothed_cov");
  request.show_progress = false;
  request.trajectory = "smoothed";
  request.output_covariance = true;
  EXPECT_THROW(
      try { RunDataset(request); } catch (const std::exception& e) {
        EXPECT_NE(std::string(e.what()).find("--trajectory=smoothed"), std::string::npos) << e.what();
        throw;
      },
      std::exception);
  request.output_covariance = false;
  request.trajectory = "lagged";
  EXPECT_THROW(RunDataset(request), std::exception);
}

// `vio run` twice as separate processes, exactly as a user would.
TEST(RunSynthetic, SameCommandTwiceGivesByteIdenticalTrajectories) {
  const std::string a = test::MakeTempDir("run_det_a");
  const std::string b = test::MakeTempDir("run_det_b");
  for (const std::string& out : {a, b}) {
    const std::string command = std::string(VIO_BINARY) + " run --dataset=" + SyntheticDataset() +
                                " --output_dir=" + out + " > " + out + "/log.txt 2>&1";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
  }
  const std::string trajectory = ReadFile(a + "/trajectory.txt");
  EXPECT_GT(trajectory.size(), 1000u);
  EXPECT_EQ(trajectory, ReadFile(b + "/trajectory.txt"));
}

// Results depend only on inputs and flags: two runs that differ in the output
// folder's name and in the size of the environment (both move the heap
// layout) write byte-identical trajectories, for the SWF, the MSCKF, batch
// (Ceres' solves on a copy laid out by id) and the SWF's offline refinement.
TEST(RunSynthetic, OutputFolderAndEnvironmentDoNotChangeTheTrajectory) {
  for (const std::string policy : {"swf", "msckf", "batch", "swf --trajectory=smoothed"}) {
    const std::string base = test::MakeTempDir("run_layout_" + std::to_string(std::hash<std::string>()(policy)));
    const std::string a = base + "/a";
    const std::string b = base + "/some/much/longer/name";
    const std::string run = std::string(VIO_BINARY) + " run --dataset=" + SyntheticDataset() + " --policy=" + policy;
    const std::string padding = "VIO_TEST_PADDING=" + std::string(3000, 'x');
    ASSERT_EQ(std::system((run + " --output_dir=" + a + " > " + base + "/a.log 2>&1").c_str()), 0) << policy;
    ASSERT_EQ(std::system(("env " + padding + " " + run + " --output_dir=" + b + " > " + base + "/b.log 2>&1").c_str()),
              0)
        << policy;
    const std::string trajectory = ReadFile(a + "/trajectory.txt");
    EXPECT_GT(trajectory.size(), 1000u) << policy;
    EXPECT_EQ(trajectory, ReadFile(b + "/trajectory.txt")) << policy;
  }
}

// --trajectory=smoothed refines every frame after the online pass: below the
// online error and the fixed-lag smoother's, near batch's final solve; its
// cost is reported.
TEST(RunSynthetic, SmoothedTrajectoryIsRefinedToNearBatch) {
  const auto ate = [](const std::string& policy, const std::string& trajectory, RefinementReport* refinement) {
    RunRequest request;
    request.dataset_dir = SyntheticDataset();
    request.output_dir = test::MakeTempDir("run_refine_" + policy + "_" + trajectory);
    request.show_progress = false;
    request.trajectory = trajectory;
    request.config.estimator.policy.policy = policy;
    // The refinement against batch on the same cost; the time offset, which SWF's windows bias on
    // this flight (-3.4 ms; docs/calibration.md, Limits) and the refinement keeps (smoothed 1.7x
    // batch), is held at its prior mean in all three runs.
    request.config.estimator.model.estimate_time_offset = false;
    const RunResult result = RunDataset(request);
    EXPECT_EQ(result.status, "ok") << policy << " " << trajectory;
    if (refinement != nullptr) *refinement = result.refinement;
    return result.evaluation ? result.evaluation->ate.rmse_m : 1e9;
  };
  RefinementReport refinement;
  const double online = ate("swf", "online", nullptr);
  const double smoothed = ate("swf", "smoothed", &refinement);
  const double batch = ate("batch", "online", nullptr);
  EXPECT_TRUE(refinement.ran);
  EXPECT_TRUE(refinement.usable);
  EXPECT_GE(refinement.iterations, 1);
  EXPECT_GT(refinement.states, 250);
  EXPECT_LT(smoothed, online);
  EXPECT_LT(smoothed, 1.2 * batch);
}

TEST(RunSynthetic, DatasetWithoutFeaturesIsAClearError) {
  const std::string dir = test::MakeTempDir("run_nofeatures");
  EurocDataset dataset = ReadEuroc(SyntheticDataset());
  dataset.features.clear();
  WriteEuroc(dataset, dir);
  RunRequest request;
  request.dataset_dir = dir;
  request.output_dir = dir + "/out";
  request.show_progress = false;
  try {
    RunDataset(request);
    FAIL() << "ran without features";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("features0/data.csv"), std::string::npos) << e.what();
  }
}

// `auto`: features0 wins when present, else the images with KLT; an explicit
// front end is kept whatever the dataset holds.
TEST(RunSynthetic, AutoFrontendPrefersFeaturesThenImages) {
  EurocDataset dataset;
  dataset.root = "dataset";
  dataset.has_images = true;
  EXPECT_EQ(ResolveFrontend("auto", dataset), "klt");
  dataset.features.push_back(FeatureObservation{});
  EXPECT_EQ(ResolveFrontend("auto", dataset), "features");
  EXPECT_EQ(ResolveFrontend("brisk", dataset), "brisk");
  dataset.has_images = false;
  EXPECT_EQ(ResolveFrontend("auto", dataset), "features");
  dataset.features.clear();
  EXPECT_THROW(ResolveFrontend("auto", dataset), std::runtime_error);
  EXPECT_EQ(ResolveFrontend("features", dataset), "features");
}

}  // namespace
}  // namespace vio::tools
