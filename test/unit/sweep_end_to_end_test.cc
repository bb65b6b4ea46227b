// `vio sweep` end to end, as real processes (VIO_BINARY) on an 8 s synthetic
// dataset the simulator makes: the table of a tiny sweep, a failed run (bad
// policy name) reported without stopping the others, resuming after an
// interruption, and jobs.txt run line by line as a cluster would.
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/simulator/simulator.h"

namespace vio::tools {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

const std::string& Dataset() {
  static const std::string dir = [] {
    SimulatorOptions options;
    options.output_dir = test::MakeTempDir("sweep_e2e") + "/synth8";
    options.duration_s = 8.0;
    Simulate(options);
    return options.output_dir;
  }();
  return dir;
}

struct Command {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

// Runs a shell command; its output goes to `log`, read back.
Command Shell(const std::string& command, const std::string& log) {
  const int status = std::system(("{ " + command + "; } > " + log + " 2>&1").c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, ReadFile(log)};
}

Command Vio(const std::string& args, const std::string& log) {
  return Shell(std::string(VIO_BINARY) + " " + args, log);
}

// The output line that contains `text` ("" when none).
std::string LineWith(const std::string& output, const std::string& text) {
  for (const std::string& line : Lines(output)) {
    if (line.find(text) != std::string::npos) return line;
  }
  return "";
}

Command Sweep(const std::string& out, const std::string& flags) {
  fs::create_directories(out);
  return Vio("sweep --datasets=" + Dataset() + " --output_dir=" + out + " --plots=false " + flags,
             out + "/../" + fs::path(out).filename().string() + ".log");
}

bool PythonCanPlot() { return std::system("/usr/bin/python3 -c 'import numpy, matplotlib' 2>/dev/null") == 0; }

TEST(SweepEndToEnd, TinySweepWritesOneOkRowPerRunAndPlots) {
  const std::string out = test::MakeTempDir("sweep_tiny") + "/sweep";
  const Command sweep = Sweep(out, "--policies=swf --window_sizes=3,5 --jobs=2 --plots=true");
  ASSERT_EQ(sweep.exit_code, 0) << sweep.output;
  EXPECT_THAT(sweep.output, HasSubstr("/2] synth8 swf_3 ok ATE "));
  EXPECT_THAT(sweep.output, HasSubstr("sweep: 2 runs, 2 ok, 0 not ok"));
  const std::vector<std::string> csv = Lines(ReadFile(out + "/results.csv"));
  ASSERT_EQ(csv.size(), 3u);
  EXPECT_EQ(csv[0].rfind("dataset,policy,window,status,exit_code,ate_rmse_m,rpe_1m_trans_pct,", 0), 0u);
  for (int row : {1, 2}) {
    std::vector<std::string> f;
    std::stringstream ss(csv[row]);
    for (std::string field; std::getline(ss, field, ',');) f.push_back(field);
    ASSERT_GE(f.size(), 7u) << csv[row];
    EXPECT_EQ(f[0] + "," + f[1] + "," + f[2] + "," + f[3] + "," + f[4],
              std::string("synth8,swf,") + (row == 1 ? "3" : "5") + ",ok,0");
    EXPECT_LT(std::stod(f[5]), 0.05) << "ATE [m] of " << csv[row];
    EXPECT_GT(std::stod(f[5]), 0.0);
  }
  EXPECT_EQ(ReadFile(out + "/runs/synth8/swf_5/done"), "exit_code=0\n");
  EXPECT_EQ(Lines(ReadFile(out + "/results.md")).size(), 9u);  // title, blank, 2 notes, blank, 2 header, 2 rows
  if (!PythonCanPlot()) GTEST_SKIP() << "no /usr/bin/python3 with numpy and matplotlib: plots not checked";
  for (const char* png : {"trajectories_synth8.png", "position_error_synth8.png", "ate_vs_cost.png"}) {
    EXPECT_GT(fs::file_size(out + "/plots/" + png), 10000u) << png << "\n" << sweep.output;
  }
  // The report: the results table, then every plot.
  const std::string report = ReadFile(out + "/report.md");
  EXPECT_THAT(report, HasSubstr("| synth8 | swf | 5 | ok |"));
  for (const char* png : {"trajectories_synth8.png", "position_error_synth8.png", "ate_vs_cost.png"}) {
    EXPECT_THAT(report, HasSubstr(std::string("](plots/") + png + ")")) << report;
  }
}

TEST(SweepEndToEnd, BadPolicyIsAFailedRunReportedByNameAndTheOthersStillRun) {
  const std::string out = test::MakeTempDir("sweep_failed") + "/sweep";
  const Command sweep = Sweep(out, "--policies=no_such_policy,swf --window_sizes=3 --jobs=1");
  EXPECT_EQ(sweep.exit_code, 1) << sweep.output;
  EXPECT_THAT(sweep.output, HasSubstr("synth8 no_such_policy_3 FAILED (exit 1): vio run: error: --policy: "
                                      "'no_such_policy' is not one of"));
  EXPECT_THAT(sweep.output, HasSubstr("] synth8 swf_3 ok ATE"));
  EXPECT_THAT(sweep.output, HasSubstr("not ok:\n  synth8 no_such_policy_3: FAILED (exit 1)"));
  const std::string csv = ReadFile(out + "/results.csv");
  EXPECT_THAT(csv, HasSubstr("\nsynth8,no_such_policy,3,failed,1,,"));
  EXPECT_THAT(csv, HasSubstr("\nsynth8,swf,3,ok,0,"));
  EXPECT_FALSE(fs::exists(out + "/runs/synth8/no_such_policy_3/done"));  // retried by the next sweep
}

// An interrupted sweep leaves folders without the `done` marker (a killed
// run, possibly with a half-written summary.json): the next sweep redoes
// exactly those, from an empty folder, and reuses the finished ones.
TEST(SweepEndToEnd, RerunRedoesOnlyTheUnfinishedRuns) {
  const std::string out = test::MakeTempDir("sweep_resume") + "/sweep";
  ASSERT_EQ(Sweep(out, "--policies=swf --window_sizes=3,4,5 --jobs=2").exit_code, 0);
  const std::string runs = out + "/runs/synth8/";
  for (const char* run : {"swf_3", "swf_4", "swf_5"}) std::ofstream(runs + run + "/sentinel") << "before\n";
  fs::remove(runs + "swf_4/done");
  std::ofstream(runs + "swf_4/summary.json") << "{\"status\": \"ok\", \"ms_per";  // killed mid-write
  fs::remove_all(runs + "swf_5");
  fs::create_directories(runs + "swf_5");  // killed right after it started
  const Command rerun = Sweep(out, "--policies=swf --window_sizes=3,4,5 --jobs=2");
  ASSERT_EQ(rerun.exit_code, 0) << rerun.output;
  EXPECT_TRUE(fs::exists(runs + "swf_3/sentinel"));
  EXPECT_FALSE(fs::exists(runs + "swf_4/sentinel"));
  EXPECT_FALSE(fs::exists(runs + "swf_5/sentinel"));
  EXPECT_EQ(ReadFile(runs + "swf_4/done"), "exit_code=0\n");
  EXPECT_THAT(LineWith(rerun.output, "synth8 swf_3 "), HasSubstr("ok ATE"));
  EXPECT_THAT(LineWith(rerun.output, "synth8 swf_3 "), HasSubstr("(finished earlier)"));
  EXPECT_THAT(LineWith(rerun.output, "synth8 swf_4 "), Not(HasSubstr("(finished earlier)")));
  EXPECT_THAT(LineWith(rerun.output, "synth8 swf_5 "), HasSubstr("ok ATE"));
  EXPECT_THAT(rerun.output, HasSubstr("sweep: 3 runs, 3 ok, 0 not ok (1 finished by an earlier sweep)"));
}

TEST(SweepEndToEnd, JobsFileRunsLineByLineThenCollectBuildsTheTable) {
  const std::string out = test::MakeTempDir("sweep_jobs") + "/sweep";
  const Command emit = Sweep(out, "--policies=swf,no_such_policy --window_sizes=3,5 --emit_jobs --init=static "
                                  "--extra_flags='--max_iterations=3'");
  ASSERT_EQ(emit.exit_code, 0) << emit.output;
  EXPECT_FALSE(fs::exists(out + "/runs"));
  const std::vector<std::string> jobs = Lines(ReadFile(out + "/jobs.txt"));
  ASSERT_EQ(jobs.size(), 4u);
  EXPECT_THAT(jobs[0], HasSubstr("'--policy=swf' '--window_size=3' '--init=static' '--max_iterations=3' >"));
  EXPECT_THAT(jobs[3], HasSubstr("'--policy=no_such_policy' '--window_size=5'"));
  const auto job = [&](int line) {  // as a Slurm array task does it
    return Shell("sed -n " + std::to_string(line) + "p " + out + "/jobs.txt | bash", out + "/job.log").exit_code;
  };
  ASSERT_EQ(job(1), 0) << ReadFile(out + "/job.log");
  EXPECT_EQ(ReadFile(out + "/runs/synth8/swf_3/done"), "exit_code=0\n");
  std::ofstream(out + "/runs/synth8/swf_3/sentinel") << "finished\n";
  EXPECT_EQ(job(1), 0);  // finished: skipped
  EXPECT_TRUE(fs::exists(out + "/runs/synth8/swf_3/sentinel"));
  EXPECT_EQ(job(3), 1);  // bad policy: fails, no marker
  EXPECT_FALSE(fs::exists(out + "/runs/synth8/no_such_policy_3/done"));
  const Command collect = Sweep(out, "--policies=swf,no_such_policy --window_sizes=3,5 --collect_only");
  EXPECT_EQ(collect.exit_code, 1) << collect.output;
  const std::string csv = ReadFile(out + "/results.csv");
  EXPECT_THAT(csv, HasSubstr("\nsynth8,swf,3,ok,0,"));
  EXPECT_THAT(csv, HasSubstr("\nsynth8,swf,5,missing,,"));
  EXPECT_THAT(csv, HasSubstr("\nsynth8,no_such_policy,3,missing,,,"));
  EXPECT_THAT(collect.output, HasSubstr("sweep: 4 runs, 1 ok, 3 not ok"));
}

TEST(SweepEndToEnd, PolicyFlagInsteadOfPoliciesIsAUsageError) {
  const std::string out = test::MakeTempDir("sweep_usage") + "/sweep";
  const Command sweep = Sweep(out, "--policy=swf --emit_jobs");
  EXPECT_EQ(sweep.exit_code, 2);
  EXPECT_THAT(sweep.output, HasSubstr("--policy: use --policies / --window_sizes in a sweep"));
}

}  // namespace
}  // namespace vio::tools
