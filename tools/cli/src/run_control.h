#pragma once
// How `vio run` stops and reports its long solves (run.cc): the request's
// stop signal, and the progress of solves that last, in the log and on the
// run's progress bar. Private to tools.
#include <optional>
#include <string>

#include "vio/cli/progress.h"
#include "vio/cli/run.h"
#include "vio/estimator/solve_control.h"

namespace vio::tools {

/// The signal that asks the run to stop (RunRequest::stop_signal); 0: go on.
inline int StopSignalOf(const RunRequest& request) { return request.stop_signal ? request.stop_signal() : 0; }

/// "SIGINT", "SIGTERM" or "signal N".
std::string SignalName(int signal);

/// Hears every solver iteration (solve_control.h). An iteration that ends a solve running for
/// kLongSolveS or more is logged (glog INFO) and drawn as the progress bar's note; shorter
/// solves (a window's, every frame) say nothing.
class SolveProgressLog {
 public:
  static constexpr double kLongSolveS = 1.0;

  /// `bar` may be null (nothing drawn).
  explicit SolveProgressLog(ProgressBar* bar) : bar_(bar) {}
  /// Names the solves from now on in the log ("solve", "final solve").
  void SetPhase(std::string phase);
  void Hear(const SolveProgress& progress);
  /// The last iteration heard, of any solve.
  const std::optional<SolveProgress>& last() const { return last_; }

 private:
  ProgressBar* bar_;
  std::string phase_ = "solve";
  bool noted_ = false;  ///< the bar shows a note
  std::optional<SolveProgress> last_;
};

/// The estimator's hooks for this run: stop when the request's stop signal is set, progress to `log`.
SolveControl MakeSolveControl(const RunRequest& request, SolveProgressLog* log);

}  // namespace vio::tools
