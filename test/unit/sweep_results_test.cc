// `vio sweep` results: reading a run folder (marker + summary.json), the
// progress line, results.csv and results.md.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/sweep/sweep.h"

namespace vio::tools {
namespace {

using ::testing::HasSubstr;

void WriteFile(const std::string& path, const std::string& text) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream(path) << text;
}

SweepRun MakeRun(const std::string& policy, int window) {
  SweepRun run;
  run.dataset_name = "V2_01";
  run.dataset_dir = "/data/V2_01";
  run.policy = policy;
  run.window_size = window;
  run.run_dir = test::MakeTempDir("sweep_results") + "/" + policy + "_" + std::to_string(window);
  return run;
}

// The shape `vio run` writes (run_output.cc), with a null RPE entry.
const char kSummary[] = R"({
  "dataset": "/data/V2_01", "policy": "swf", "window_size": 10, "status": "ok",
  "frames": 100, "ms_per_frame": 6.125, "real_time_factor": 8.5,
  "stage_ms_per_frame": {"total": 6.1}, "peak_memory_mb": 190.25,
  "frontend": {"frames": 100, "ok": true},
  "evaluation": {
    "alignment": "posyaw", "T_gt_est": {"p_m": [1, -2.5e-1, 3], "q_xyzw": [0, 0, 0, 1]}, "scale": 1,
    "ate": {"rmse_m": 0.0204, "mean_m": 0.018},
    "rpe": [
      {"length_m": 1, "trans_pct": 1.25, "rot_deg_per_m": 0.5, "num_pairs": 20},
      {"length_m": 10, "trans_pct": null, "rot_deg_per_m": null, "num_pairs": 0}
    ]
  }
}
)";

SweepResult FinishedOkRun() {
  const SweepRun run = MakeRun("swf", 10);
  WriteFile(run.run_dir + "/summary.json", kSummary);
  WriteFile(run.run_dir + "/done", "exit_code=0\n");
  return ReadRunResult(run);
}

SweepResult FailedRun() {
  SweepResult failed;
  failed.run = MakeRun("msckf", 5);
  failed.status = "failed";
  failed.exit_code = 1;
  failed.message = "vio run: error: --policy: 'msckf' is not one of swf";
  return failed;
}

TEST(SweepResults, FinishedRunIsReadFromItsMarkerAndSummary) {
  const SweepResult r = FinishedOkRun();
  EXPECT_EQ(r.status, "ok");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_DOUBLE_EQ(r.ate_rmse_m, 0.0204);
  EXPECT_DOUBLE_EQ(r.ms_per_frame, 6.125);
  EXPECT_DOUBLE_EQ(r.real_time_factor, 8.5);
  EXPECT_DOUBLE_EQ(r.peak_memory_mb, 190.25);
  ASSERT_EQ(r.rpe.size(), 2u);
  EXPECT_DOUBLE_EQ(r.rpe[0].trans_pct, 1.25);
  EXPECT_EQ(r.rpe[1].length_m, 10.0);
  EXPECT_TRUE(std::isnan(r.rpe[1].trans_pct));
}

TEST(SweepResults, FolderWithoutMarkerIsUnfinishedEvenWithASummary) {
  const SweepRun run = MakeRun("swf", 5);
  WriteFile(run.run_dir + "/summary.json", kSummary);
  WriteFile(run.run_dir + "/run.log", "frame 10\n");
  EXPECT_FALSE(IsRunFinished(run));
  const SweepResult r = ReadRunResult(run);
  EXPECT_EQ(r.status, "missing");
  EXPECT_TRUE(std::isnan(r.ate_rmse_m));
}

TEST(SweepResults, MalformedSummaryIsAFailedRunNamingTheFile) {
  const SweepRun run = MakeRun("swf", 30);
  WriteFile(run.run_dir + "/summary.json", "{\"status\": \"ok\", \"ms_per_frame\": ");
  WriteFile(run.run_dir + "/done", "exit_code=0\n");
  const SweepResult r = ReadRunResult(run);
  EXPECT_EQ(r.status, "failed");
  EXPECT_THAT(r.message, HasSubstr("summary.json"));
}

TEST(SweepResults, ProgressLines) {
  EXPECT_EQ(ProgressLine(FinishedOkRun(), 3, 20), "[3/20] V2_01 swf_10 ok ATE 0.020 m 6.1 ms/frame");
  EXPECT_EQ(ProgressLine(FailedRun(), 4, 20),
            "[4/20] V2_01 msckf_5 FAILED (exit 1): vio run: error: --policy: 'msckf' is not one of swf");
  SweepResult reused = FinishedOkRun();
  reused.reused = true;
  EXPECT_THAT(ProgressLine(reused, 1, 2), HasSubstr("(finished earlier)"));
}

TEST(SweepResults, CsvHasOneRowPerRunAndEmptyFieldsForMissingNumbers) {
  const std::string csv = ResultsCsv({FinishedOkRun(), FailedRun()});
  std::istringstream lines(csv);
  std::string header, ok_row, failed_row, extra;
  std::getline(lines, header);
  std::getline(lines, ok_row);
  std::getline(lines, failed_row);
  EXPECT_FALSE(std::getline(lines, extra));
  EXPECT_EQ(header,
            "dataset,policy,window,status,exit_code,ate_rmse_m,rpe_1m_trans_pct,rpe_1m_rot_deg_per_m,"
            "rpe_10m_trans_pct,rpe_10m_rot_deg_per_m,ms_per_frame,real_time_factor,peak_memory_mb,nees_pose,"
            "nees_position,nees_orientation,message,run_dir");
  EXPECT_EQ(ok_row.rfind("V2_01,swf,10,ok,0,0.0204,1.25,0.5,,,6.125,8.5,190.25,,,,,/", 0), 0u) << ok_row;
  EXPECT_EQ(failed_row.rfind("V2_01,msckf,5,failed,1,,,,,,,,,,,,vio run: error: --policy: 'msckf' is not one of swf,/", 0),
            0u)
      << failed_row;
}

TEST(SweepResults, MarkdownTableHasOneRowPerRun) {
  const std::string md = ResultsMarkdown({FinishedOkRun(), FailedRun()});
  EXPECT_THAT(md, HasSubstr("| dataset | policy | window | status | ATE RMSE [m] | RPE 1 m [%] | RPE 10 m [%] |"));
  EXPECT_THAT(md, HasSubstr("| V2_01 | swf | 10 | ok | 0.020 | 1.25 | - | 6.1 | 8.5 | 190 |"));
  EXPECT_THAT(md, HasSubstr("| V2_01 | msckf | 5 | FAILED (exit 1) | - | - | - | - | - | - |"));
}

}  // namespace
}  // namespace vio::tools
