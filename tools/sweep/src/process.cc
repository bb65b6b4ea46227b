// `vio sweep`: runs as child processes, N at a time, with resumable folders.
#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <stdexcept>
#include <thread>

#include "internal.h"
#include "vio/sweep/sweep.h"

namespace vio::tools {
namespace {

namespace fs = std::filesystem;

int ExitCodeOf(int wait_status) {
  if (WIFEXITED(wait_status)) return WEXITSTATUS(wait_status);
  if (WIFSIGNALED(wait_status)) return 128 + WTERMSIG(wait_status);
  return 255;
}

// A fresh, empty run folder (what an interrupted run left is removed).
void ClearRunDir(const SweepRun& run) {
  std::error_code ec;
  fs::remove_all(run.run_dir, ec);
  if (!ec) fs::create_directories(run.run_dir, ec);
  if (ec) throw std::runtime_error(run.run_dir + ": cannot prepare the run folder: " + ec.message());
}

pid_t StartRun(const SweepRequest& request, const SweepRun& run) {
  const std::vector<std::string> argv = RunArguments(request, run);
  ClearRunDir(run);
  return SpawnProcess(argv, run.run_dir + "/run.log");
}

// After the process ended: the marker when it left a summary and was not
// stopped by a signal, then the result.
SweepResult FinishRun(const SweepRun& run, int exit_code) {
  if (IsInterruptedExitCode(exit_code)) {
    SweepResult result;
    result.run = run;
    result.status = "interrupted";
    result.exit_code = exit_code;
    result.message = "stopped by a signal; the next sweep redoes it";
    return result;
  }
  if (fs::exists(run.run_dir + "/summary.json")) WriteDoneMarker(run.run_dir, exit_code);
  SweepResult result = ReadRunResult(run);
  if (result.status == "missing") {
    result.status = "failed";
    result.exit_code = exit_code;
    result.message = LastLine(run.run_dir + "/run.log");
  }
  return result;
}

}  // namespace

pid_t SpawnProcess(const std::vector<std::string>& argv, const std::string& log_path) {
  std::vector<char*> c_argv;
  for (const std::string& arg : argv) c_argv.push_back(const_cast<char*>(arg.c_str()));
  c_argv.push_back(nullptr);
  const int log_fd = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (log_fd < 0) throw std::runtime_error(log_path + ": cannot open: " + std::strerror(errno));
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid == 0) {  // child: only async-signal-safe calls until exec
    // Ends with the sweep: an orphan must not write into a folder the next sweep redoes.
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(128 + SIGTERM);
    dup2(log_fd, STDOUT_FILENO);
    dup2(log_fd, STDERR_FILENO);
    execv(c_argv[0], c_argv.data());
    const char message[] = "vio sweep: cannot execute the program\n";
    const ssize_t ignored = write(STDERR_FILENO, message, sizeof(message) - 1);
    (void)ignored;
    _exit(127);
  }
  const int fork_errno = errno;
  close(log_fd);
  if (pid < 0) throw std::runtime_error(std::string("fork failed: ") + std::strerror(fork_errno));
  return pid;
}

bool PollProcess(pid_t pid, int* exit_code) {
  int status = 0;
  const pid_t ended = waitpid(pid, &status, WNOHANG);
  if (ended == 0) return false;
  if (ended < 0) throw std::runtime_error("waitpid failed: " + std::string(std::strerror(errno)));
  *exit_code = ExitCodeOf(status);
  return true;
}

int WaitProcess(pid_t pid) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) throw std::runtime_error("waitpid failed: " + std::string(std::strerror(errno)));
  }
  return ExitCodeOf(status);
}

void WriteDoneMarker(const std::string& run_dir, int exit_code) {
  const std::string temp = run_dir + "/done.tmp";
  {
    std::ofstream out(temp);
    out << "exit_code=" << exit_code << "\n";
    if (!out) throw std::runtime_error(temp + ": cannot write");
  }
  fs::rename(temp, run_dir + "/done");
}

std::string LastLine(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::string last;
  while (std::getline(in, line)) {
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  }
  return last;
}

bool IsRunFinished(const SweepRun& run) { return fs::exists(run.run_dir + "/done"); }

SweepResult ExecuteRun(const SweepRequest& request, const SweepRun& run) {
  return FinishRun(run, WaitProcess(StartRun(request, run)));
}

std::vector<SweepResult> RunSweep(const SweepRequest& request, std::ostream& progress) {
  const std::vector<SweepRun> plan = PlanSweep(request);
  const int total = static_cast<int>(plan.size());
  std::vector<SweepResult> results(plan.size());
  std::vector<size_t> pending;
  int finished = 0;
  for (size_t i = 0; i < plan.size(); ++i) {
    RunArguments(request, plan[i]);  // bad flags fail before anything runs
    if (!IsRunFinished(plan[i])) {
      pending.push_back(i);
      continue;
    }
    results[i] = ReadRunResult(plan[i]);
    results[i].reused = true;
    progress << ProgressLine(results[i], ++finished, total) << std::endl;
  }
  std::vector<std::pair<size_t, pid_t>> running;  // (plan index, process)
  size_t next = 0;
  int forwarded = 0;  // the stop signal, once passed on to the running runs
  while (next < pending.size() || !running.empty()) {
    if (const int signal = request.stop_signal ? request.stop_signal() : 0; signal != 0 && forwarded == 0) {
      for (const auto& [index, pid] : running) kill(pid, signal);
      forwarded = signal;
      for (; next < pending.size(); ++next) {  // nothing more starts
        results[pending[next]].run = plan[pending[next]];
        results[pending[next]].message = "not started: the sweep was stopped";
      }
    }
    while (static_cast<int>(running.size()) < std::max(1, request.jobs) && next < pending.size()) {
      running.emplace_back(pending[next], StartRun(request, plan[pending[next]]));
      ++next;
    }
    for (auto it = running.begin(); it != running.end();) {
      int exit_code = 0;
      if (!PollProcess(it->second, &exit_code)) {
        ++it;
        continue;
      }
      results[it->first] = FinishRun(plan[it->first], exit_code);
      progress << ProgressLine(results[it->first], ++finished, total) << std::endl;
      it = running.erase(it);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return results;
}

std::vector<SweepResult> CollectSweep(const SweepRequest& request) {
  std::vector<SweepResult> results;
  for (const SweepRun& run : PlanSweep(request)) results.push_back(ReadRunResult(run));
  return results;
}

}  // namespace vio::tools
