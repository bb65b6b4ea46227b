#pragma once
// Child processes of `vio sweep` (fork/exec, output to a log file). Private
// to tools.
#include <sys/types.h>

#include <string>
#include <vector>

namespace vio::tools {

/// Starts argv[0] with argv, stdout and stderr into `log_path` (truncated).
/// Throws std::runtime_error when the log cannot be opened or fork fails; an
/// exec failure shows as exit code 127 with the reason in the log.
pid_t SpawnProcess(const std::vector<std::string>& argv, const std::string& log_path);

/// True once `pid` has ended; then *exit_code is its exit status, or
/// 128 + signal number when a signal ended it. Does not block.
bool PollProcess(pid_t pid, int* exit_code);

/// Waits for `pid` to end; returns its exit code as PollProcess does.
int WaitProcess(pid_t pid);

/// Writes the `done` marker of a run folder ("exit_code=<n>"): a temp file,
/// then a rename, so that the marker is either absent or complete.
void WriteDoneMarker(const std::string& run_dir, int exit_code);

/// The last non-empty line of a text file ("" when none).
std::string LastLine(const std::string& path);

}  // namespace vio::tools
