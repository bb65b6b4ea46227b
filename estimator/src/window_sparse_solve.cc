// Window::SolveSparse: Levenberg-Marquardt over the window's variable blocks
// on a copy of their cost laid out by id, landmarks eliminated first (Schur
// complement), the reduced state system solved sparsely. Ceres orders the
// blocks of one elimination group by address; in the copy every block lives
// in one buffer filled in id order, so that order is the id order and the
// solve depends only on the values (batch's solves; bundle adjustment).
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <unordered_map>
#include <vector>

#include <glog/logging.h>

#include "quadratic_landmark_factor.h"
#include "solve_control_callback.h"
#include "vio/estimator/window.h"

namespace vio {
namespace {

ceres::LinearSolverType SchurSolverFor(const std::string& linear_solver) {
  if (linear_solver == "dense") return ceres::DENSE_SCHUR;
  if (linear_solver == "iterative") return ceres::ITERATIVE_SCHUR;
  return ceres::SPARSE_SCHUR;
}

ceres::LinearSolverType NormalSolverFor(const std::string& linear_solver) {
  if (linear_solver == "dense") return ceres::DENSE_NORMAL_CHOLESKY;
  if (linear_solver == "iterative") return ceres::CGNR;
  return ceres::SPARSE_NORMAL_CHOLESKY;
}

// Ceres' options for `options`, the Schur solvers when `ordering` has something to eliminate.
ceres::Solver::Options LinearSolverOptions(const SolverOptions& options,
                                           const std::shared_ptr<ceres::ParameterBlockOrdering>& ordering) {
  ceres::Solver::Options solver;
  solver.max_num_iterations = options.max_iterations;
  solver.function_tolerance = options.function_tolerance;
  if (options.max_solver_time_s > 0) solver.max_solver_time_in_seconds = options.max_solver_time_s;
  solver.num_threads = options.num_threads;
  solver.logging_type = ceres::SILENT;
  if (options.linear_solver == "sparse_full") {  // the whole system, segments' interiors first
    solver.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    solver.linear_solver_ordering = ordering;
    return solver;
  }
  const bool eliminable = ordering->GroupSize(0) > 0;
  solver.linear_solver_type =
      eliminable ? SchurSolverFor(options.linear_solver) : NormalSolverFor(options.linear_solver);
  if (eliminable) solver.linear_solver_ordering = ordering;
  if (options.linear_solver == "iterative") {
    solver.preconditioner_type = eliminable ? ceres::SCHUR_JACOBI : ceres::JACOBI;
  }
  return solver;
}

// A block's place in a copy: states by id (pose, then speed/bias), landmarks by id, then the
// calibration blocks (time offset, extrinsics).
using CopyRank = std::tuple<int, std::int64_t, int>;

CopyRank RankOf(const BlockKey& key) {
  switch (key.kind) {
    case BlockKey::Kind::kPose:
      return {0, key.id, 0};
    case BlockKey::Kind::kSpeedBias:
      return {0, key.id, 1};
    case BlockKey::Kind::kLandmark:
      return {1, key.id, 0};
    case BlockKey::Kind::kTimeOffset:
      return {2, 0, 0};
    case BlockKey::Kind::kExtrinsics:
      return {3, 0, 0};
  }
  return {4, 0, 0};
}

}  // namespace

// The window's blocks a set of residuals touches, copied into one buffer in
// id order; `copy_of` maps a window block to its copy (a lookup only: the
// order is `blocks`').
struct Window::IdOrderedCopy {
  std::vector<double> values;
  std::vector<const double*> blocks;  ///< window blocks, in copy order
  std::unordered_map<const double*, double*> copy_of;
};

SolveReport Window::SolveSparse(const SolverOptions& options) {
  const VariableIds variable = VariableIdsOf();
  if (variable.states.empty() && variable.landmarks.empty()) return SolveReport();
  const Leaving solved = SolvedOf(variable);
  const std::vector<ceres::ResidualBlockId> residuals = ResidualOrderOf(solved, LeavingKeysOf(solved));
  return SolveCopy(options, residuals, {}, CopyOf(residuals, {}));
}

Window::Leaving Window::SolvedOf(const VariableIds& variable) {
  Leaving solved = LeavingOf(variable.states, variable.landmarks);
  for (double* block : CalibrationBlocks()) {
    if (!problem_->IsParameterBlockConstant(block)) solved.blocks.insert(block);  // and its prior
  }
  return solved;
}

Window::VariableIds Window::VariableIdsOf() const {
  return {{variable_states_.begin(), variable_states_.end()}, {variable_landmarks_.begin(), variable_landmarks_.end()}};
}

// Every block the residuals and `extra` touch, states (pose, speed/bias) then landmarks, by id.
Window::IdOrderedCopy Window::CopyOf(const std::vector<ceres::ResidualBlockId>& residuals,
                                     const LandmarkFactors& extra) const {
  std::unordered_map<const double*, CopyRank> touched;
  const auto touch = [&](const double* block) {
    const auto key = block_keys_.find(block);
    CHECK(key != block_keys_.end()) << "a residual touches a block that is no state, landmark or calibration";
    touched.emplace(block, RankOf(key->second));
  };
  for (ceres::ResidualBlockId residual : residuals) {
    std::vector<double*> blocks;
    problem_->GetParameterBlocksForResidualBlock(residual, &blocks);
    for (const double* block : blocks) touch(block);
  }
  for (const auto& [block, factor] : extra) touch(block);
  std::vector<std::pair<CopyRank, const double*>> order;
  order.reserve(touched.size());
  for (const auto& [block, rank] : touched) order.emplace_back(rank, block);
  std::sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  IdOrderedCopy copy;
  std::vector<size_t> offsets;
  for (const auto& [rank, block] : order) {
    copy.blocks.push_back(block);
    offsets.push_back(copy.values.size());
    copy.values.insert(copy.values.end(), block, block + problem_->ParameterBlockSize(block));
  }
  for (size_t k = 0; k < copy.blocks.size(); ++k) copy.copy_of[copy.blocks[k]] = copy.values.data() + offsets[k];
  return copy;
}

// The observations from constant states drop out: their landmarks get one
// quadratic factor each instead (QuadraticLandmarkFactor).
SolveReport Window::SolveSparse(const SolverOptions& options, const FrozenObservations& frozen) {
  const VariableIds variable = VariableIdsOf();
  if (variable.states.empty() && variable.landmarks.empty()) return SolveReport();
  const Leaving solved = SolvedOf(variable);
  std::vector<std::unique_ptr<ceres::CostFunction>> factors;
  LandmarkFactors extra;
  for (LandmarkId id : variable.landmarks) {
    const auto it = frozen.landmarks.find(id);
    if (it == frozen.landmarks.end()) continue;
    factors.push_back(QuadraticLandmarkFactor(it->second));
    extra.emplace_back(landmarks_.at(id).p_w, factors.back().get());
  }
  const std::vector<ceres::ResidualBlockId> residuals = RecentResidualOrderOf(solved);
  return SolveCopy(options, residuals, extra, CopyOf(residuals, extra));
}

std::vector<ceres::ResidualBlockId> Window::RecentResidualOrderOf(const Leaving& solved) const {
  std::vector<ceres::ResidualBlockId> order;
  for (const Prior& prior : priors_) {
    if (Touches(prior, solved)) order.push_back(prior.residual);
  }
  // The IMU factors into and out of the solved states, by their later state.
  std::set<StateId> edges;
  for (StateId id : solved.states) {
    if (imu_edges_.count(id)) edges.insert(id);
    const auto out = imu_edges_.upper_bound(id);
    if (out != imu_edges_.end() && out->second.from == id) edges.insert(out->first);
  }
  for (StateId to : edges) order.push_back(imu_edges_.at(to).residual);
  for (StateId id : solved.states) {
    for (auto it = observations_.lower_bound({id, LandmarkId(std::numeric_limits<std::int64_t>::min())});
         it != observations_.end() && it->first.first == id; ++it) {
      order.push_back(it->second.residual);
    }
  }
  for (const ObservationKey& key : AnchoredKeysOf(solved)) order.push_back(anchored_points_.at(key));
  return order;
}

// The elimination group (0 first) of every state and landmark block.
// Schur solvers: the landmarks not tied by a prior (an independent set), then
// the rest. sparse_full: the states cut into segments of kSegmentStates by id;
// group 0 holds every state but each segment's last and the landmarks seen
// from one segment only, group 1 the segments' last states and the landmarks
// seen from several (a whole sequence re-observes landmarks across it). Each
// segment's interior is eliminated on its own, with fill only among its states
// and landmarks and its two end states; the separator, group 1, is one small
// dense system. Landmarks first would leave a nearly dense system over every
// pose; states first (the IMU chain) a dense block of every state against
// every landmark.
std::unordered_map<const double*, int> Window::EliminationGroups(const std::string& linear_solver,
                                                                 const std::vector<const double*>& blocks) const {
  constexpr int kSegmentStates = 20;
  const bool segments = linear_solver == "sparse_full";
  const std::set<const double*> in_prior = BlocksInPriors();
  std::map<StateId, int> place;  // sparse_full: each state's place in id order
  if (segments) {
    for (const auto& [id, s] : states_) place.emplace(id, static_cast<int>(place.size()));
  }
  const auto segment = [&](StateId id) { return place.at(id) / kSegmentStates; };
  std::unordered_map<const double*, int> group;
  for (const double* block : blocks) {
    const BlockKey& key = block_keys_.at(block);
    if (key.kind == BlockKey::Kind::kPose || key.kind == BlockKey::Kind::kSpeedBias) {
      const bool separator = !segments || place.at(StateId(key.id)) % kSegmentStates == kSegmentStates - 1;
      group[block] = separator ? 1 : 0;
    } else if (key.kind == BlockKey::Kind::kLandmark) {
      const Landmark& landmark = landmarks_.at(LandmarkId(key.id));
      const bool one_segment = !segments || landmark.observed_from.empty() ||
                               segment(*landmark.observed_from.begin()) == segment(*landmark.observed_from.rbegin());
      const bool eliminable = landmark.anchored_to.empty() && !in_prior.count(landmark.p_w);
      group[block] = one_segment && eliminable ? 0 : 1;
    } else {
      group[block] = 1;  // calibration: seen by every observation
    }
  }
  return group;
}

// LM on the copy.
SolveReport Window::SolveCopy(const SolverOptions& options, const std::vector<ceres::ResidualBlockId>& residuals,
                              const LandmarkFactors& extra, const IdOrderedCopy& ids) {
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem copy(problem_options);
  const std::unordered_map<const double*, int> groups = EliminationGroups(options.linear_solver, ids.blocks);
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (const double* block : ids.blocks) {
    double* c = ids.copy_of.at(block);
    copy.AddParameterBlock(c, problem_->ParameterBlockSize(block),
                           const_cast<ceres::Manifold*>(problem_->GetManifold(block)));
    const bool constant = problem_->IsParameterBlockConstant(block);
    if (constant) copy.SetParameterBlockConstant(c);
    ordering->AddElementToGroup(c, constant ? 1 : groups.at(block));
  }
  for (ceres::ResidualBlockId residual : residuals) {
    std::vector<double*> window_blocks;
    problem_->GetParameterBlocksForResidualBlock(residual, &window_blocks);
    for (double*& block : window_blocks) block = ids.copy_of.at(block);
    copy.AddResidualBlock(const_cast<ceres::CostFunction*>(problem_->GetCostFunctionForResidualBlock(residual)),
                          const_cast<ceres::LossFunction*>(problem_->GetLossFunctionForResidualBlock(residual)),
                          window_blocks);
  }
  for (const auto& [block, factor] : extra) copy.AddResidualBlock(factor, nullptr, ids.copy_of.at(block));
  ceres::Solver::Options solver = LinearSolverOptions(options, ordering);
  SolveControlCallback control(solve_control_, solver.max_num_iterations);
  solver.callbacks.push_back(&control);
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &copy, &summary);
  VLOG(2) << "sparse solve of " << ids.blocks.size() << " blocks: " << summary.BriefReport();
  SolveReport report;
  report.iterations = static_cast<int>(summary.iterations.size());
  report.initial_cost = summary.initial_cost;
  report.final_cost = summary.final_cost;
  report.usable = summary.IsSolutionUsable();
  report.converged = summary.termination_type == ceres::CONVERGENCE;
  report.stopped = control.stopped();
  if (report.stopped) ++health_.stopped_solves;
  if (!report.usable) {
    ++health_.failed_solves;
    return report;
  }
  for (const double* block : ids.blocks) {
    if (problem_->IsParameterBlockConstant(block)) continue;
    std::memcpy(const_cast<double*>(block), ids.copy_of.at(block), sizeof(double) * problem_->ParameterBlockSize(block));
  }
  return report;
}

}  // namespace vio
