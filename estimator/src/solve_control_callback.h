#pragma once
// The caller's SolveControl inside ceres::Solve (Window::LevenbergMarquardt,
// Window::SolveCopy): progress after each iteration, and a stop request that
// ends the solve at the iterate reached.

#include <ceres/iteration_callback.h>

#include "vio/estimator/solve_control.h"

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

 private:
  const SolveControl& control_;
  int max_iterations_;
  double initial_cost_ = 0;
  bool stopped_ = false;
};

}  // namespace vio
