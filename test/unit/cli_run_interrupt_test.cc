// A run stopped by SIGINT (Ctrl-C) or SIGTERM (a scheduler's time limit)
// keeps what it estimated: the real binary (VIO_BINARY) on a synthetic flight,
// signalled once its trajectory.txt holds some frames (polled, never timed),
// exits 130 / 143 with status interrupted, and its frames are the first lines
// of the uninterrupted run's. A second signal ends it at once. In process:
// batch stopped inside its final solve writes the iterate it reached.
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/cli/run.h"
#include "vio/simulator/simulator.h"

namespace vio::tools {
namespace {

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::vector<std::string> PoseLines(const std::string& path) {
  std::vector<std::string> lines;
  std::istringstream in(ReadFile(path));
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] != '#') lines.push_back(line);
  }
  return lines;
}

// 60 s of synthetic flight (1200 frames): a run takes seconds, so a signal
// sent after its first frames lands long before its end.
const std::string& LongDataset() {
  static const std::string dir = [] {
    SimulatorOptions options;
    options.output_dir = test::MakeTempDir("run_interrupt") + "/dataset";
    options.duration_s = 60.0;
    options.seed = 5;
    Simulate(options);
    return options.output_dir;
  }();
  return dir;
}

// 15 s: batch's final solve over it takes a few seconds.
const std::string& ShortDataset() {
  static const std::string dir = [] {
    SimulatorOptions options;
    options.output_dir = test::MakeTempDir("run_interrupt_short") + "/dataset";
    options.duration_s = 15.0;
    options.seed = 5;
    Simulate(options);
    return options.output_dir;
  }();
  return dir;
}

std::vector<std::string> RunArgs(const std::string& output_dir, const std::string& policy) {
  return {VIO_BINARY, "run", "--dataset=" + LongDataset(), "--output_dir=" + output_dir, "--policy=" + policy};
}

// `vio` as a child process (stdout and stderr to log); `own_group`: in a
// process group of its own, as a shell's foreground job (its id is the pid).
pid_t Start(const std::vector<std::string>& args, const std::string& log, bool own_group = false) {
  std::vector<char*> argv;
  for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    if (own_group) setpgid(0, 0);
    if (freopen(log.c_str(), "w", stdout) == nullptr || dup2(fileno(stdout), STDERR_FILENO) < 0) _exit(126);
    execv(argv[0], argv.data());
    _exit(127);
  }
  return pid;
}

// Exit code, or 1000 + signal for a process a signal ended.
int Wait(pid_t pid) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
  }
  return WIFSIGNALED(status) ? 1000 + WTERMSIG(status) : WEXITSTATUS(status);
}

// Polls until trajectory.txt holds `poses` poses; false when the process ended first.
bool WaitForPoses(pid_t pid, const std::string& path, size_t poses) {
  while (PoseLines(path).size() < poses) {
    if (waitpid(pid, nullptr, WNOHANG) != 0) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

std::string SummaryString(const std::string& dir, const std::string& key) {
  const std::string summary = ReadFile(dir + "/summary.json");
  const size_t at = summary.find("\"" + key + "\": ");
  if (at == std::string::npos) return "";
  const size_t begin = at + key.size() + 4;
  return summary.substr(begin, summary.find_first_of(",\n", begin) - begin);
}

int SummaryInt(const std::string& dir, const std::string& key) { return std::stoi(SummaryString(dir, key)); }

// The uninterrupted run of a policy, once: its trajectory.txt.
const std::vector<std::string>& CompleteRun(const std::string& policy) {
  static std::map<std::string, std::vector<std::string>> runs;
  if (!runs.count(policy)) {
    const std::string dir = test::MakeTempDir("run_complete_" + policy);
    EXPECT_EQ(Wait(Start(RunArgs(dir, policy), dir + "/log.txt")), 0) << ReadFile(dir + "/log.txt");
    runs[policy] = PoseLines(dir + "/trajectory.txt");
  }
  return runs[policy];
}

class StoppedRun : public ::testing::TestWithParam<int> {};

TEST_P(StoppedRun, KeepsTheFramesSoFarAndExitsWithTheSignalsCode) {
  const int signal = GetParam();
  const std::vector<std::string>& complete = CompleteRun("swf");
  ASSERT_GT(complete.size(), 1000u);
  const std::string dir = test::MakeTempDir("run_stopped");
  const pid_t pid = Start(RunArgs(dir, "swf"), dir + "/log.txt");
  ASSERT_TRUE(WaitForPoses(pid, dir + "/trajectory.txt", 100)) << ReadFile(dir + "/log.txt");
  kill(pid, signal);
  EXPECT_EQ(Wait(pid), 128 + signal) << ReadFile(dir + "/log.txt");
  EXPECT_EQ(SummaryString(dir, "status"), "\"interrupted\"");
  const std::vector<std::string> written = PoseLines(dir + "/trajectory.txt");
  ASSERT_GE(written.size(), 100u);
  ASSERT_LT(written.size(), complete.size());
  EXPECT_EQ(SummaryInt(dir, "frames_estimated"), static_cast<int>(written.size()));
  EXPECT_GT(SummaryInt(dir, "frames_after_stop"), 0);
  for (size_t i = 0; i < written.size(); ++i) ASSERT_EQ(written[i], complete[i]) << "pose " << i;
  // timing.csv: one row per frame written (and its header).
  EXPECT_EQ(PoseLines(dir + "/timing.csv").size(), written.size());
  EXPECT_NE(ReadFile(dir + "/log.txt").find("status interrupted"), std::string::npos);
}

INSTANTIATE_TEST_SUITE_P(Signals, StoppedRun, ::testing::Values(SIGINT, SIGTERM));

// Batch stopped while the frames stream in: its online estimates so far, and
// summary.json says so (its final solve never ran).
TEST(StoppedRun, BatchKeepsItsOnlineFrames) {
  const std::string dir = test::MakeTempDir("run_stopped_batch");
  const pid_t pid = Start(RunArgs(dir, "batch"), dir + "/log.txt");
  ASSERT_TRUE(WaitForPoses(pid, dir + "/trajectory.txt", 100)) << ReadFile(dir + "/log.txt");
  kill(pid, SIGTERM);
  EXPECT_EQ(Wait(pid), 128 + SIGTERM) << ReadFile(dir + "/log.txt");
  EXPECT_EQ(SummaryString(dir, "status"), "\"interrupted\"");
  EXPECT_EQ(SummaryString(dir, "trajectory"), "\"online\"");
  const std::vector<std::string> written = PoseLines(dir + "/trajectory.txt");
  EXPECT_GE(written.size(), 100u);
  EXPECT_EQ(SummaryInt(dir, "frames_estimated"), static_cast<int>(written.size()));
}

// Two signals (both pending while the run is stopped, delivered together):
// the first asks to stop, the second ends the process at once; the frames
// streamed before stay.
TEST(StoppedRun, ASecondSignalEndsAtOnce) {
  const std::string dir = test::MakeTempDir("run_stopped_twice");
  const pid_t pid = Start(RunArgs(dir, "swf"), dir + "/log.txt");
  ASSERT_TRUE(WaitForPoses(pid, dir + "/trajectory.txt", 100)) << ReadFile(dir + "/log.txt");
  kill(pid, SIGSTOP);
  kill(pid, SIGINT);
  kill(pid, SIGTERM);
  kill(pid, SIGCONT);
  const int code = Wait(pid);
  EXPECT_TRUE(code == 1000 + SIGINT || code == 1000 + SIGTERM) << code << "\n" << ReadFile(dir + "/log.txt");
  EXPECT_GE(PoseLines(dir + "/trajectory.txt").size(), 100u);
}

// In process: batch's final solve asked to stop after its first iteration
// keeps that iterate; the status, the signal and the message say so.
TEST(StoppedRun, BatchStoppedInItsFinalSolveWritesItsIterate) {
  const std::string complete_dir = test::MakeTempDir("run_batch_complete");
  RunRequest request;
  request.dataset_dir = ShortDataset();
  request.output_dir = complete_dir;
  request.show_progress = false;
  request.config.estimator.policy.policy = "batch";
  const RunResult complete = RunDataset(request);
  ASSERT_EQ(complete.status, "ok");
  const size_t frames = PoseLines(complete_dir + "/trajectory.txt").size();

  request.output_dir = test::MakeTempDir("run_batch_stopped");
  int asked_after_last_frame = 0;
  // Every frame is streamed before the final solve: from then on, the second question (after the
  // solve's first iteration) stops it.
  request.stop_signal = [&] {
    if (PoseLines(request.output_dir + "/trajectory.txt").size() < frames) return 0;
    return ++asked_after_last_frame >= 2 ? SIGTERM : 0;
  };
  const RunResult stopped = RunDataset(request);
  EXPECT_EQ(stopped.status, "interrupted");
  EXPECT_EQ(stopped.stop_signal, SIGTERM);
  EXPECT_EQ(stopped.trajectory, "final");
  EXPECT_EQ(stopped.frames_estimated, complete.frames_estimated);
  ASSERT_FALSE(stopped.problems.empty());
  EXPECT_NE(stopped.problems.back().find("in the final solve"), std::string::npos) << stopped.problems.back();
  EXPECT_NE(stopped.problems.back().find("iteration 1 of"), std::string::npos) << stopped.problems.back();
  const std::vector<std::string> written = PoseLines(request.output_dir + "/trajectory.txt");
  ASSERT_EQ(written.size(), frames);
  EXPECT_NE(written, PoseLines(complete_dir + "/trajectory.txt")) << "one iteration is not the converged solve";
}

// `vio sweep` stopped while its first run goes: SIGTERM to the sweep alone
// (it passes it on), or SIGINT to its whole process group (Ctrl-C: every run
// gets it directly too, and the copy the sweep forwards is not a second
// signal). The run writes its summary (interrupted) but no `done` marker, the
// run not started has none either, and the same command then finishes both
// (checked once).
class StoppedSweep : public ::testing::TestWithParam<bool> {};

TEST_P(StoppedSweep, LeavesItsRunsUnfinishedAndResumes) {
  const bool whole_group = GetParam();
  const std::string out = test::MakeTempDir("sweep_stopped");
  const std::vector<std::string> args = {VIO_BINARY, "sweep", "--datasets=" + LongDataset(), "--runs=swf:10,msckf:10",
                                         "--output_dir=" + out, "--plots=false", "--jobs=1"};
  const std::string swf = out + "/runs/dataset/swf_10", msckf = out + "/runs/dataset/msckf_10";
  const pid_t sweep = Start(args, out + "/sweep1.log", /*own_group=*/true);
  ASSERT_TRUE(WaitForPoses(sweep, swf + "/trajectory.txt", 100)) << ReadFile(out + "/sweep1.log");
  const int signal = whole_group ? SIGINT : SIGTERM;
  kill(whole_group ? -sweep : sweep, signal);
  EXPECT_EQ(Wait(sweep), 128 + signal) << ReadFile(out + "/sweep1.log");
  EXPECT_EQ(SummaryString(swf, "status"), "\"interrupted\"") << ReadFile(swf + "/run.log");
  EXPECT_GE(PoseLines(swf + "/trajectory.txt").size(), 100u);
  EXPECT_FALSE(test::PathExists(swf + "/done"));
  EXPECT_FALSE(test::PathExists(msckf + "/done"));
  EXPECT_NE(ReadFile(out + "/sweep1.log").find("interrupted (exit " + std::to_string(128 + signal) + ")"),
            std::string::npos)
      << ReadFile(out + "/sweep1.log");
  if (whole_group) return;  // resuming is the same either way

  EXPECT_EQ(Wait(Start(args, out + "/sweep2.log")), 0) << ReadFile(out + "/sweep2.log");
  EXPECT_EQ(SummaryString(swf, "status"), "\"ok\"");
  EXPECT_TRUE(test::PathExists(swf + "/done"));
  EXPECT_TRUE(test::PathExists(msckf + "/done"));
  EXPECT_EQ(PoseLines(swf + "/trajectory.txt"), CompleteRun("swf"));
}

INSTANTIATE_TEST_SUITE_P(Signals, StoppedSweep, ::testing::Values(false, true));

}  // namespace
}  // namespace vio::tools
