#pragma once
// The caller's hooks into the window's solves (Window::SetSolveControl,
// Estimator::SetSolveControl): a stop request asked between iterations, so
// that a long solve (batch's final solve) ends promptly when a run is
// stopped, and progress heard after each iteration. No hook: no effect; a
// stop request that stays false never changes a result.
#include <functional>

namespace vio {

/// One finished iteration of a solve, as the progress hook hears it.
struct SolveProgress {
  int iteration = 0;        ///< iterations finished in this solve (Ceres: its iteration number, 0 = the start)
  int max_iterations = 0;   ///< the solve's cap
  double initial_cost = 0;  ///< at the start of the solve
  double cost = 0;          ///< after this iteration
  double elapsed_s = 0;     ///< wall time since the solve started [s]
};

struct SolveControl {
  /// Asked before each iteration: true ends the solve there, keeping the iterate reached
  /// (SolveReport::stopped, WindowHealth::stopped_solves). Empty: never.
  std::function<bool()> stop;
  /// Told after each iteration. Empty: nobody.
  std::function<void(const SolveProgress&)> progress;

  bool StopRequested() const { return stop && stop(); }
  void Report(const SolveProgress& p) const {
    if (progress) progress(p);
  }
};

}  // namespace vio
