// Window's second operation, Gauss-Newton steps (paper §2.2): the column
// layout by ids, the exact GN path (gauss_newton.h) and the Levenberg-Marquardt
// path through ceres::Solve with id-ordered elimination groups.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <glog/logging.h>

#include "keyed_residuals.h"
#include "solve_control_callback.h"
#include "vio/estimator/window.h"

namespace vio {
namespace {

double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

std::set<LandmarkId> Window::LandmarksInPriors() const {
  std::set<LandmarkId> in_prior;
  for (const Prior& prior : priors_) {
    for (const BlockKey& key : prior.keys) {
      if (key.kind == BlockKey::Kind::kLandmark) in_prior.insert(LandmarkId(key.id));
    }
  }
  return in_prior;
}

std::vector<ceres::ResidualBlockId> Window::ResidualOrder() const {
  std::vector<ceres::ResidualBlockId> order;
  order.reserve(static_cast<size_t>(problem_->NumResidualBlocks()));
  for (const Prior& prior : priors_) order.push_back(prior.residual);
  for (const auto& [to, edge] : imu_edges_) order.push_back(edge.residual);
  for (const auto& [key, observation] : observations_) order.push_back(observation.residual);
  for (const auto& [key, residual] : anchored_points_) order.push_back(residual);
  CHECK_EQ(static_cast<int>(order.size()), problem_->NumResidualBlocks()) << "a residual block the window does not know";
  return order;
}

// A state's residuals are one range of the map (keyed by state first), a
// landmark's are listed by it (`by`): no walk over every residual.
template <typename Residuals>
std::set<Window::ObservationKey> Window::KeysOf(const Residuals& residuals, std::set<StateId> Landmark::*by,
                                                const Leaving& leaving) const {
  std::set<ObservationKey> keys;
  for (StateId id : leaving.states) {
    for (auto it = residuals.lower_bound({id, LandmarkId(std::numeric_limits<std::int64_t>::min())});
         it != residuals.end() && it->first.first == id; ++it) {
      keys.insert(it->first);
    }
  }
  for (LandmarkId id : leaving.landmarks) {
    for (StateId from : landmarks_.at(id).*by) keys.insert({from, id});
  }
  return keys;
}

std::set<Window::ObservationKey> Window::ObservationKeysOf(const Leaving& leaving) const {
  return KeysOf(observations_, &Landmark::observed_from, leaving);
}

std::set<Window::ObservationKey> Window::AnchoredKeysOf(const Leaving& leaving) const {
  return KeysOf(anchored_points_, &Landmark::anchored_to, leaving);
}

bool Window::Touches(const Prior& prior, const Leaving& leaving) const {
  return std::any_of(prior.keys.begin(), prior.keys.end(), [&](const BlockKey& key) { return leaving.Has(key); });
}

bool Window::Touches(StateId to, const ImuEdge& edge, const Leaving& leaving) const {
  return leaving.states.count(edge.from) > 0 || leaving.states.count(to) > 0;
}

Window::LeavingKeys Window::LeavingKeysOf(const Leaving& leaving) const {
  return {ObservationKeysOf(leaving), AnchoredKeysOf(leaving)};
}

KeyedResiduals Window::ResidualOrderOf(const Leaving& leaving, const LeavingKeys& keys) const {
  KeyedResiduals order;
  for (const Prior& prior : priors_) {
    if (Touches(prior, leaving)) order.Add(prior.residual, prior.keys);
  }
  for (const auto& [to, edge] : imu_edges_) {
    if (Touches(to, edge, leaving)) order.Add(edge.residual, ImuKeys(edge.from, to));
  }
  const std::vector<BlockKey> calibration = CalibrationKeys();
  for (const auto& [state, landmark] : keys.observations) {
    order.Add(observations_.at({state, landmark}).residual, PointKeys(state, landmark), calibration);
  }
  AddAnchoredPoints(keys.anchored, &order);
  return order;
}

void Window::AddAnchoredPoints(const std::set<ObservationKey>& keys, KeyedResiduals* order) const {
  for (const auto& [state, landmark] : keys) order->Add(anchored_points_.at({state, landmark}), PointKeys(state, landmark));
}

// Dense columns: every pose, the time offset, then every speed/bias block (both by state id),
// then the landmarks tied by a prior; the speed/bias blocks are the chain the
// solver may eliminate first (gauss_newton.h). With the poses side by side, the poses
// seeing a landmark are one contiguous range of columns (a track is seen from
// consecutive states), so its Schur update is one rank-3 update in place.
GaussNewtonLayout Window::Layout() const {
  const std::set<LandmarkId> in_prior = LandmarksInPriors();
  GaussNewtonLayout layout;
  layout.residuals = ResidualOrder();
  const auto variable = [this](const double* block) { return !problem_->IsParameterBlockConstant(block); };
  for (const auto& [id, s] : states_) {
    if (variable(s.pose)) layout.dense.push_back(const_cast<double*>(s.pose));
  }
  // The calibration blocks next to the poses: a landmark's Schur update over its poses and the offset
  // stays one contiguous range when the newest poses see it.
  for (double* block : CalibrationBlocks()) {
    if (variable(block)) layout.dense.push_back(block);
  }
  for (const auto& [id, s] : states_) {
    if (!variable(s.speed_bias)) continue;
    layout.chain.push_back(static_cast<int>(layout.dense.size()));
    layout.dense.push_back(const_cast<double*>(s.speed_bias));
  }
  for (const auto& [id, landmark] : landmarks_) {
    if (!variable(landmark.p_w)) continue;
    auto& group = in_prior.count(id) ? layout.dense : layout.eliminated;
    group.push_back(const_cast<double*>(landmark.p_w));
  }
  return layout;
}

// Landmarks (group 0) are eliminated first by the Schur complement; the
// state blocks follow, one group each in id order. Ceres orders the blocks
// inside one group by address, so LM runs depend on the heap layout in the
// last digits (gn does not: Layout() is by id). Landmarks tied together by a
// prior are not an independent set: they join the states, after them.
std::shared_ptr<ceres::ParameterBlockOrdering> Window::SchurOrdering() const {
  const std::set<LandmarkId> in_prior = LandmarksInPriors();
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  int group = 1;
  for (const auto& [id, s] : states_) {
    ordering->AddElementToGroup(const_cast<double*>(s.pose), group++);
    ordering->AddElementToGroup(const_cast<double*>(s.speed_bias), group++);
  }
  for (double* block : CalibrationBlocks()) ordering->AddElementToGroup(block, group++);
  for (const auto& [id, landmark] : landmarks_) {
    const bool eliminated = in_prior.count(id) == 0;
    ordering->AddElementToGroup(const_cast<double*>(landmark.p_w), eliminated ? 0 : group++);
  }
  return ordering;
}

// For sparse Cholesky of the whole normal equations: the states first, then
// the landmarks. A whole sequence sees few landmarks many times, so
// eliminating the states (a chain, little fill) leaves a small dense system
// over the landmarks; eliminating the landmarks first would leave a large,
// nearly dense one over the states.
std::shared_ptr<ceres::ParameterBlockOrdering> Window::StatesFirstOrdering() const {
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (const auto& [id, s] : states_) {
    ordering->AddElementToGroup(const_cast<double*>(s.pose), 0);
    ordering->AddElementToGroup(const_cast<double*>(s.speed_bias), 0);
  }
  for (double* block : CalibrationBlocks()) ordering->AddElementToGroup(block, 0);
  for (const auto& [id, landmark] : landmarks_) ordering->AddElementToGroup(const_cast<double*>(landmark.p_w), 1);
  return ordering;
}

// Ceres' linear solver and elimination ordering for `linear_solver`.
void Window::ChooseLinearSolver(const std::string& linear_solver, ceres::Solver::Options* solver) const {
  if (linear_solver == "sparse_full") {
    solver->linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    solver->linear_solver_ordering = StatesFirstOrdering();
    return;
  }
  solver->linear_solver_ordering = SchurOrdering();
  // With nothing to eliminate (every landmark tied into a prior, as in
  // EKF-SLAM) the Schur complement only adds overhead.
  const bool eliminable = solver->linear_solver_ordering->GroupSize(0) > 0;
  if (!eliminable) solver->linear_solver_ordering.reset();
  if (linear_solver == "iterative") {
    solver->linear_solver_type = eliminable ? ceres::ITERATIVE_SCHUR : ceres::CGNR;
    solver->preconditioner_type = eliminable ? ceres::SCHUR_JACOBI : ceres::JACOBI;
  } else if (linear_solver == "sparse") {
    solver->linear_solver_type = eliminable ? ceres::SPARSE_SCHUR : ceres::SPARSE_NORMAL_CHOLESKY;
  } else {
    solver->linear_solver_type = eliminable ? ceres::DENSE_SCHUR : ceres::DENSE_NORMAL_CHOLESKY;
  }
}

Eigen::MatrixXd Window::Information(const std::vector<StateId>& state_ids,
                                    const std::vector<LandmarkId>& landmark_ids) {
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks = Blocks(state_ids, landmark_ids);
  evaluate.residual_blocks = ResidualOrder();
  ceres::CRSMatrix crs;
  if (!problem_->Evaluate(evaluate, nullptr, nullptr, nullptr, &crs)) {
    throw std::runtime_error("Window::Information: the cost does not evaluate at the current values");
  }
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int row = 0; row < crs.num_rows; ++row) {
    for (int k = crs.rows[row]; k < crs.rows[row + 1]; ++k) J(row, crs.cols[k]) = crs.values[k];
  }
  return J.transpose() * J;
}

SolveReport Window::Solve(const SolverOptions& options) {
  if (options.step == "gn") return GaussNewton(options.max_iterations, /*until_converged=*/true, options);
  ceres::Solver::Options solver;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = options.function_tolerance;
  return LevenbergMarquardt(solver, options);
}

SolveReport Window::TakeSteps(int steps, const SolverOptions& options) {
  CHECK_GE(steps, 1);
  if (options.step == "gn") return GaussNewton(steps, /*until_converged=*/false, options);
  ceres::Solver::Options solver;
  solver.max_num_iterations = steps;
  solver.function_tolerance = 0;
  solver.gradient_tolerance = 0;
  solver.parameter_tolerance = 0;
  return LevenbergMarquardt(solver, options);
}

// Undamped steps. A step whose end point does not evaluate (it overshot a
// landmark behind a camera: a depth far from what its disparity says) is
// undone, the observations that failed there are dropped as outliers, and the
// step is taken again on the window without them; it does not count as one of
// the `max_steps`.
SolveReport Window::GaussNewton(int max_steps, bool until_converged, const SolverOptions& options) {
  SolveReport report;
  const auto lay_out = [this] {
    if (gauss_newton_ == nullptr) {
      gauss_newton_ = std::make_unique<GaussNewtonSolver>(problem_.get(), Layout());
    } else {
      gauss_newton_->Relayout(Layout());
    }
  };
  lay_out();
  GaussNewtonSolver* solver = gauss_newton_.get();
  const auto start = std::chrono::steady_clock::now();
  for (int k = 0; k < max_steps; ++k) {
    if (solve_control_.StopRequested()) {
      report.stopped = true;
      ++health_.stopped_solves;
      break;
    }
    const GaussNewtonStep step = solver->Step();
    if (k == 0) report.initial_cost = report.final_cost = step.cost;
    if (!step.ok) {
      report.usable = false;
      ++health_.failed_solves;
      break;
    }
    double cost = 0;
    if (!solver->Cost(&cost)) {
      const std::vector<ObservationKey> outliers = UnevaluableObservations();
      solver->UndoStep();
      ++health_.rejected_steps;
      LOG(WARNING) << "gauss-newton: step " << k << " reached a point that does not evaluate; undone, "
                   << outliers.size() << " observation(s) that fail there dropped";
      if (outliers.empty()) break;
      DropOutlierObservations(outliers);
      lay_out();
      --k;
      continue;
    }
    ++report.iterations;
    report.final_cost = cost;
    solve_control_.Report({report.iterations, max_steps, report.initial_cost, cost, SecondsSince(start)});
    VLOG(2) << "gn step " << k << ": cost " << step.cost << " -> " << cost << ", |dx| " << step.step_norm;
    const bool small_change = std::abs(step.cost - cost) <= options.function_tolerance * step.cost;
    const bool small_step =
        step.step_norm <= options.parameter_tolerance * (step.values_norm + options.parameter_tolerance);
    if (until_converged && (small_change || small_step)) {
      report.converged = true;
      break;
    }
  }
  return report;
}

SolveReport Window::LevenbergMarquardt(const ceres::Solver::Options& base, const SolverOptions& options) {
  ceres::Solver::Options solver = base;
  ChooseLinearSolver(options.linear_solver, &solver);
  if (options.max_solver_time_s > 0) solver.max_solver_time_in_seconds = options.max_solver_time_s;
  solver.num_threads = options.num_threads;
  solver.minimizer_progress_to_stdout = false;
  solver.logging_type = ceres::SILENT;
  SolveControlCallback control(solve_control_, solver.max_num_iterations);
  solver.callbacks.push_back(&control);
  ceres::Solver::Summary summary;
  ceres::Solve(solver, problem_.get(), &summary);
  const SolveReport report = control.ReportOf(summary);
  if (report.stopped) ++health_.stopped_solves;
  if (!report.usable) ++health_.failed_solves;
  return report;
}

}  // namespace vio
