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
#include <unordered_set>
#include <utility>
#include <vector>

#include <glog/logging.h>

#include "keyed_residuals.h"
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

// The blocks of a copy, in id order (RankOf), their values in one buffer.
struct IdOrderedCopy {
  std::vector<double> values;
  std::vector<BlockKey> keys;
  std::vector<double*> window_blocks;  ///< the window's block of each key
  std::vector<std::size_t> offsets;    ///< where each block starts in `values`
  std::unordered_map<BlockKey, std::size_t, BlockKeyHash> place;  ///< a key's place in `keys` (a lookup only)

  double* Of(const BlockKey& key) { return values.data() + offsets[place.at(key)]; }
};

namespace {

// Adds the copy's blocks to `copy` (constant where the window's are), in their order and elimination groups.
std::shared_ptr<ceres::ParameterBlockOrdering> AddBlocks(const ceres::Problem& window, IdOrderedCopy& ids,
                                                          const std::vector<int>& groups, ceres::Problem* copy) {
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (std::size_t k = 0; k < ids.keys.size(); ++k) {
    const double* block = ids.window_blocks[k];
    double* c = ids.values.data() + ids.offsets[k];
    copy->AddParameterBlock(c, window.ParameterBlockSize(block), const_cast<ceres::Manifold*>(window.GetManifold(block)));
    const bool constant = window.IsParameterBlockConstant(block);
    if (constant) copy->SetParameterBlockConstant(c);
    ordering->AddElementToGroup(c, constant ? 1 : groups[k]);
  }
  return ordering;
}

// Adds each residual, on the copy's blocks of its keys, and each of `extra`, to `copy`.
void AddResiduals(const ceres::Problem& window, const KeyedResiduals& residuals,
                  const std::vector<std::pair<LandmarkId, ceres::CostFunction*>>& extra, IdOrderedCopy& ids,
                  ceres::Problem* copy) {
  std::vector<double*> blocks;
  for (std::size_t k = 0; k < residuals.size(); ++k) {
    blocks.clear();
    for (const BlockKey* key = residuals.begin(k); key != residuals.end(k); ++key) blocks.push_back(ids.Of(*key));
    const ceres::ResidualBlockId id = residuals.ids[k];
    copy->AddResidualBlock(const_cast<ceres::CostFunction*>(window.GetCostFunctionForResidualBlock(id)),
                           const_cast<ceres::LossFunction*>(window.GetLossFunctionForResidualBlock(id)), blocks);
  }
  for (const auto& [landmark, factor] : extra) copy->AddResidualBlock(factor, nullptr, ids.Of(BlockKey::Landmark(landmark)));
}

}  // namespace

SolveReport Window::SolveSparse(const SolverOptions& options) {
  const VariableIds variable = VariableIdsOf();
  if (variable.states.empty() && variable.landmarks.empty()) return SolveReport();
  const Leaving solved = SolvedOf(variable);
  return SolveCopy(options, ResidualOrderOf(solved, LeavingKeysOf(solved)), {});
}

Window::Leaving Window::SolvedOf(const VariableIds& variable) {
  Leaving solved = LeavingOf(variable.states, variable.landmarks);
  for (const auto& [block, key] : KeyedCalibrationBlocks()) {
    if (!problem_->IsParameterBlockConstant(block)) solved.calibration.insert(key);  // and its prior
  }
  return solved;
}

Window::VariableIds Window::VariableIdsOf() const {
  return {{variable_states_.begin(), variable_states_.end()}, {variable_landmarks_.begin(), variable_landmarks_.end()}};
}

// Every block the residuals and `extra` touch, states (pose, speed/bias) then landmarks, by id.
IdOrderedCopy Window::CopyOf(const KeyedResiduals& residuals, const LandmarkFactors& extra) const {
  std::unordered_set<BlockKey, BlockKeyHash> touched(residuals.keys.begin(), residuals.keys.end());
  for (const auto& [landmark, factor] : extra) touched.insert(BlockKey::Landmark(landmark));
  IdOrderedCopy copy;
  copy.keys.assign(touched.begin(), touched.end());
  std::sort(copy.keys.begin(), copy.keys.end(), [](const BlockKey& a, const BlockKey& b) { return RankOf(a) < RankOf(b); });
  for (const BlockKey& key : copy.keys) {
    double* block = BlockOf(key);
    copy.place.emplace(key, copy.window_blocks.size());
    copy.window_blocks.push_back(block);
    copy.offsets.push_back(copy.values.size());
    copy.values.insert(copy.values.end(), block, block + problem_->ParameterBlockSize(block));
  }
  return copy;
}

// The observations from constant states drop out: their landmarks get one
// quadratic factor each instead (QuadraticLandmarkFactor).
SolveReport Window::SolveSparse(const SolverOptions& options, const FrozenObservations& frozen) {
  const VariableIds variable = VariableIdsOf();
  if (variable.states.empty() && variable.landmarks.empty()) return SolveReport();
  std::vector<std::unique_ptr<ceres::CostFunction>> factors;
  LandmarkFactors extra;
  for (LandmarkId id : variable.landmarks) {
    const auto it = frozen.landmarks.find(id);
    if (it == frozen.landmarks.end()) continue;
    factors.push_back(QuadraticLandmarkFactor(it->second));
    extra.emplace_back(id, factors.back().get());
  }
  return SolveCopy(options, RecentResidualOrderOf(SolvedOf(variable)), extra);
}

KeyedResiduals Window::RecentResidualOrderOf(const Leaving& solved) const {
  KeyedResiduals order;
  for (const Prior& prior : priors_) {
    if (Touches(prior, solved)) order.Add(prior.residual, prior.keys);
  }
  // The IMU factors into and out of the solved states, by their later state.
  std::set<StateId> edges;
  for (StateId id : solved.states) {
    if (imu_edges_.count(id)) edges.insert(id);
    const auto out = imu_edges_.upper_bound(id);
    if (out != imu_edges_.end() && out->second.from == id) edges.insert(out->first);
  }
  for (StateId to : edges) order.Add(imu_edges_.at(to).residual, ImuKeys(imu_edges_.at(to).from, to));
  const std::vector<BlockKey> calibration = CalibrationKeys();
  for (StateId id : solved.states) {
    for (auto it = observations_.lower_bound({id, LandmarkId(std::numeric_limits<std::int64_t>::min())});
         it != observations_.end() && it->first.first == id; ++it) {
      order.Add(it->second.residual, PointKeys(id, it->first.second), calibration);
    }
  }
  AddAnchoredPoints(AnchoredKeysOf(solved), &order);
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
std::vector<int> Window::EliminationGroups(const std::string& linear_solver, const std::vector<BlockKey>& blocks) const {
  constexpr int kSegmentStates = 20;
  const bool segments = linear_solver == "sparse_full";
  const std::set<LandmarkId> in_prior = LandmarksInPriors();
  std::map<StateId, int> place;  // sparse_full: each state's place in id order
  if (segments) {
    for (const auto& [id, s] : states_) place.emplace(id, static_cast<int>(place.size()));
  }
  const auto segment = [&](StateId id) { return place.at(id) / kSegmentStates; };
  std::vector<int> groups;
  groups.reserve(blocks.size());
  for (const BlockKey& key : blocks) {
    if (key.kind == BlockKey::Kind::kPose || key.kind == BlockKey::Kind::kSpeedBias) {
      const bool separator = !segments || place.at(StateId(key.id)) % kSegmentStates == kSegmentStates - 1;
      groups.push_back(separator ? 1 : 0);
    } else if (key.kind == BlockKey::Kind::kLandmark) {
      const Landmark& landmark = landmarks_.at(LandmarkId(key.id));
      const bool one_segment = !segments || landmark.observed_from.empty() ||
                               segment(*landmark.observed_from.begin()) == segment(*landmark.observed_from.rbegin());
      const bool eliminable = landmark.anchored_to.empty() && !in_prior.count(landmark.id);
      groups.push_back(one_segment && eliminable ? 0 : 1);
    } else {
      groups.push_back(1);  // calibration: seen by every observation
    }
  }
  return groups;
}

// LM on the copy; the list of residuals is freed once they are in it.
SolveReport Window::SolveCopy(const SolverOptions& options, KeyedResiduals residuals, const LandmarkFactors& extra) {
  IdOrderedCopy ids = CopyOf(residuals, extra);
  ceres::Problem::Options problem_options;
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem copy(problem_options);
  const auto ordering = AddBlocks(*problem_, ids, EliminationGroups(options.linear_solver, ids.keys), &copy);
  AddResiduals(*problem_, residuals, extra, ids, &copy);
  residuals = KeyedResiduals();  // in the copy now: its memory is not held through the solve
  ceres::Solver::Options solver = LinearSolverOptions(options, ordering);
  SolveControlCallback control(solve_control_, solver.max_num_iterations);
  solver.callbacks.push_back(&control);
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &copy, &summary);
  VLOG(2) << "sparse solve of " << ids.keys.size() << " blocks: " << summary.BriefReport();
  const SolveReport report = control.ReportOf(summary);
  if (report.stopped) ++health_.stopped_solves;
  if (!report.usable) {
    ++health_.failed_solves;
    return report;
  }
  for (std::size_t k = 0; k < ids.keys.size(); ++k) {
    double* block = ids.window_blocks[k];
    if (problem_->IsParameterBlockConstant(block)) continue;
    std::memcpy(block, ids.values.data() + ids.offsets[k], sizeof(double) * problem_->ParameterBlockSize(block));
  }
  return report;
}

}  // namespace vio
