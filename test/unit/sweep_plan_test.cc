// `vio sweep` planning: the combinations, their run folders, the `vio run`
// command lines and the shell lines of jobs.txt.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/sweep/sweep.h"

namespace vio::tools {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

// Two empty "dataset" folders (planning only checks that they are folders).
SweepRequest TwoDatasetRequest() {
  const std::string root = test::MakeTempDir("sweep_plan");
  std::filesystem::create_directories(root + "/data/V2_01");
  std::filesystem::create_directories(root + "/data/MH_04");
  SweepRequest request;
  request.datasets = {root + "/data/V2_01/", root + "/data/MH_04"};
  request.policies = {"swf", "msckf"};
  request.window_sizes = {5, 30};
  request.output_dir = root + "/out";
  request.vio_binary = "/opt/vio/bin/vio";
  return request;
}

TEST(SweepPlan, EveryCombinationInDatasetPolicyWindowOrder) {
  const SweepRequest request = TwoDatasetRequest();
  const std::vector<SweepRun> plan = PlanSweep(request);
  ASSERT_EQ(plan.size(), 8u);
  EXPECT_EQ(plan[0].Label(), "V2_01 swf_5");
  EXPECT_EQ(plan[1].Label(), "V2_01 swf_30");
  EXPECT_EQ(plan[2].Label(), "V2_01 msckf_5");
  EXPECT_EQ(plan[7].Label(), "MH_04 msckf_30");
  EXPECT_EQ(plan[3].run_dir, request.output_dir + "/runs/V2_01/msckf_30");
  EXPECT_TRUE(std::filesystem::path(plan[3].dataset_dir).is_absolute());
}

TEST(SweepPlan, BadInputIsAnErrorBeforeAnythingRuns) {
  SweepRequest request = TwoDatasetRequest();
  request.datasets.push_back(request.datasets.front() + "../V2_01");  // same folder name twice
  EXPECT_THROW(PlanSweep(request), std::invalid_argument);
  request = TwoDatasetRequest();
  request.datasets.push_back("/no/such/dataset");
  EXPECT_THROW(PlanSweep(request), std::invalid_argument);
  request = TwoDatasetRequest();
  request.window_sizes = {0};
  EXPECT_THROW(PlanSweep(request), std::invalid_argument);
  request = TwoDatasetRequest();
  request.policies = {"../evil"};
  EXPECT_THROW(PlanSweep(request), std::invalid_argument);
}

TEST(SweepPlan, RunArgumentsSetDatasetFolderPolicyWindowThenTheExtraFlags) {
  SweepRequest request = TwoDatasetRequest();
  request.run_flags = {"--init=groundtruth"};
  const SweepRun run = PlanSweep(request)[2];
  EXPECT_THAT(RunArguments(request, run),
              ElementsAre("/opt/vio/bin/vio", "run", "--dataset=" + run.dataset_dir, "--output_dir=" + run.run_dir,
                          "--policy=msckf", "--window_size=5", "--init=groundtruth"));
  request.run_flags = {"--window_size=7"};
  EXPECT_THROW(RunArguments(request, run), std::invalid_argument);
  request.run_flags = {"groundtruth"};
  EXPECT_THROW(RunArguments(request, run), std::invalid_argument);
}

// policy:window:K runs: the local map's keyframes are a run's own flag, its folder and label say them.
TEST(SweepPlan, LocalMapRunsPassTheirKeyframes) {
  SweepRequest request = TwoDatasetRequest();
  request.combinations = {{"swf", 10, 0}, {"swf", 10, 8}, {"msckf", 10, 8}};
  const std::vector<SweepRun> plan = PlanSweep(request);
  ASSERT_EQ(plan.size(), 6u);
  EXPECT_EQ(plan[0].Label(), "V2_01 swf_10");
  EXPECT_EQ(plan[1].Label(), "V2_01 swf+map8_10");
  EXPECT_EQ(plan[1].run_dir, request.output_dir + "/runs/V2_01/swf+map8_10");
  EXPECT_THAT(RunArguments(request, plan[2]),
              ElementsAre("/opt/vio/bin/vio", "run", "--dataset=" + plan[2].dataset_dir,
                          "--output_dir=" + plan[2].run_dir, "--policy=msckf", "--window_size=10",
                          "--local_map_keyframes=8"));
  request.run_flags = {"--local_map_keyframes=4"};
  EXPECT_NO_THROW(RunArguments(request, plan[0]));  // forwarded to the runs without their own
  EXPECT_THROW(RunArguments(request, plan[1]), std::invalid_argument);
  request.combinations.push_back({"swf", 10, 8});
  EXPECT_THROW(PlanSweep(request), std::invalid_argument);
}

TEST(SweepPlan, JobLineSkipsFinishedRunsAndWritesTheMarkerOnlyWithASummary) {
  const SweepRequest request = TwoDatasetRequest();
  const SweepRun run = PlanSweep(request)[0];
  const std::string line = JobCommand(request, run);
  EXPECT_EQ(line.find('\n'), std::string::npos);
  EXPECT_EQ(line.rfind("d=" + ShellQuote(run.run_dir) + "; [ -f \"$d/done\" ] || {", 0), 0u) << line;
  EXPECT_THAT(line, HasSubstr("rm -rf \"$d\" && mkdir -p \"$d\" && '/opt/vio/bin/vio' 'run' "));
  EXPECT_THAT(line, HasSubstr("'--policy=swf' '--window_size=5' >\"$d/run.log\" 2>&1; rc=$?;"));
  EXPECT_THAT(line, HasSubstr("if [ -f \"$d/summary.json\" ] && [ $rc -ne 130 ] && [ $rc -ne 143 ]; then echo "
                              "\"exit_code=$rc\" >\"$d/done.tmp\" && mv \"$d/done.tmp\" \"$d/done\"; fi; exit $rc; }"));
}

// The job line run by a shell, with a stand-in `vio` that writes its summary and exits with
// $FAKE_RC: `done` follows any exit code but a signal's (130, 143: the run was stopped, redo it).
TEST(SweepPlan, JobLineLeavesARunStoppedByASignalUnfinished) {
  SweepRequest request = TwoDatasetRequest();
  request.vio_binary = std::filesystem::path(request.output_dir).parent_path().string() + "/fake_vio.sh";
  {
    std::ofstream script(request.vio_binary);
    script << "#!/bin/sh\nfor a; do case \"$a\" in --output_dir=*) d=\"${a#--output_dir=}\";; esac; done\n"
              "echo '{\"status\": \"x\"}' > \"$d/summary.json\"; exit $FAKE_RC\n";
  }
  std::filesystem::permissions(request.vio_binary, std::filesystem::perms::owner_all);
  const SweepRun run = PlanSweep(request)[0];
  for (const int rc : {0, 1, 130, 143}) {
    std::filesystem::remove_all(run.run_dir);
    const std::string command = "FAKE_RC=" + std::to_string(rc) + " sh -c " + ShellQuote(JobCommand(request, run));
    const int status = std::system(command.c_str());
    EXPECT_EQ(WEXITSTATUS(status), rc);
    EXPECT_TRUE(std::filesystem::exists(run.run_dir + "/summary.json")) << rc;
    EXPECT_EQ(std::filesystem::exists(run.run_dir + "/done"), !IsInterruptedExitCode(rc)) << rc;
  }
}

TEST(SweepPlan, ShellQuotingAndFlagSplitting) {
  EXPECT_EQ(ShellQuote("a b"), "'a b'");
  EXPECT_EQ(ShellQuote("it's"), "'it'\\''s'");
  EXPECT_THAT(SplitFlags("  --init=groundtruth\t--calibration='/a b/c' \"--x=1 2\" "),
              ElementsAre("--init=groundtruth", "--calibration=/a b/c", "--x=1 2"));
  EXPECT_TRUE(SplitFlags("   ").empty());
  EXPECT_THROW(SplitFlags("--a='b"), std::invalid_argument);
}

}  // namespace
}  // namespace vio::tools
