#include "vio/cli/stop_signal.h"

#include <unistd.h>

#include <atomic>
#include <climits>
#include <csignal>
#include <cstring>
#include <string>

namespace vio::tools {
namespace {

std::atomic<int> stop_signal{0};
static_assert(std::atomic<int>::is_always_lock_free, "the signal handler needs a lock-free flag");
// The parent is a `vio` (a sweep): a signal it sends after the first only repeats the request.
bool parent_forwards = false;

std::string ExecutableOf(const std::string& proc_dir) {
  char path[PATH_MAX];
  const ssize_t n = readlink((proc_dir + "/exe").c_str(), path, sizeof(path) - 1);
  return n > 0 ? std::string(path, static_cast<size_t>(n)) : std::string();
}

void Say(const char* text) {
  const ssize_t ignored = write(STDERR_FILENO, text, std::strlen(text));
  (void)ignored;
}

// Async-signal-safe: atomics, getppid, write, signal, raise.
void OnStopSignal(int signo, siginfo_t* info, void* /*context*/) {
  const bool from_parent = info != nullptr && info->si_code == SI_USER && info->si_pid == getppid();
  int none = 0;
  if (stop_signal.compare_exchange_strong(none, signo)) {
    Say(signo == SIGINT ? "\nvio: SIGINT: stopping after this frame or solver iteration and writing what was "
                           "estimated (again: stop at once)\n"
                         : "\nvio: SIGTERM: stopping after this frame or solver iteration and writing what was "
                           "estimated (again: stop at once)\n");
    return;
  }
  if (from_parent && parent_forwards) return;
  std::signal(signo, SIG_DFL);
  std::raise(signo);  // delivered when the handler returns: the default action ends the process
}

}  // namespace

void InstallStopSignalHandlers() {
  const std::string self = ExecutableOf("/proc/self");
  parent_forwards = !self.empty() && self == ExecutableOf("/proc/" + std::to_string(getppid()));
  struct sigaction action = {};
  action.sa_sigaction = &OnStopSignal;
  action.sa_flags = SA_SIGINFO | SA_RESTART;
  sigemptyset(&action.sa_mask);
  sigaddset(&action.sa_mask, SIGINT);
  sigaddset(&action.sa_mask, SIGTERM);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

int StopSignal() { return stop_signal.load(std::memory_order_relaxed); }

}  // namespace vio::tools
