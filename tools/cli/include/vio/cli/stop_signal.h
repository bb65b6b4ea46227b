#pragma once
// Ctrl-C (SIGINT) and SIGTERM (a scheduler's time limit) stop `vio run` and
// `vio sweep` cleanly. The handler only records the signal (async-signal-safe);
// the run polls StopSignal() between frames and solver iterations, ends, and
// writes what it estimated. A second signal ends the process at once (the
// default action), except the copy a parent `vio sweep` forwards to its runs
// after the same signal reached them directly (a terminal's or Slurm's signal
// goes to every process): that one only repeats the request.
namespace vio::tools {

/// Installs the handlers for SIGINT and SIGTERM (once per process).
void InstallStopSignalHandlers();
/// The signal that asked to stop (SIGINT or SIGTERM); 0 while none came.
int StopSignal();
/// The exit code of a process stopped by `signal`: 128 + signal (130 for SIGINT, 143 for SIGTERM).
inline int InterruptedExitCode(int signal) { return 128 + signal; }

}  // namespace vio::tools
