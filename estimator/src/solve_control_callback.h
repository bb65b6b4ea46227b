#pragma once
// The caller's SolveControl inside ceres::Solve (Window::LevenbergMarquardt,
// Window::SolveCopy): progress after each iteration, and a stop request that
// ends the solve at the iterate reached.

#include <ceres/iteration_callback.h>
#include <ceres/solver.h>

#include "vio/estimator/solve_control.h"
#include "vio/estimator/window.h"

namespace vio {

class SolveControlCallback final : public ceres::IterationCallback {
 public:
  SolveControlCallback(const SolveControl& control, int max_iterations)
      : control_(control), max_iterations_(max_iterations) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (summary.iteration == 0) initial_cost_ = summary.cost;
    control_.Report({summary.iteration, max_iterations_, initial_cost_, summary.cost,
                     summary.cumulative_time_in_seconds});
    if (!control_.StopRequested()) return ceres::SOLVER_CONTINUE;
    stopped_ = true;
    return ceres::SOLVER_TERMINATE_SUCCESSFULLY;  // keeps the iterate reached
  }
  bool stopped() const { return stopped_; }
  /// What the solve that ran with this callback did, from its summary.
  SolveReport ReportOf(const ceres::Solver::Summary& summary) const {
    SolveReport report;
    report.iterations = static_cast<int>(summary.iterations.size());
    report.initial_cost = summary.initial_cost;
    report.final_cost = summary.final_cost;
    report.usable = summary.IsSolutionUsable();
    report.converged = summary.termination_type == ceres::CONVERGENCE;
    report.stopped = stopped_;
    return report;
  }

 private:
  const SolveControl& control_;
  int max_iterations_;
  double initial_cost_ = 0;
  bool stopped_ = false;
};

}  // namespace vio
