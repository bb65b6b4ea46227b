#include "vio/estimator/window.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <glog/logging.h>

#include "vio/estimator/imu_factor.h"
#include "vio/estimator/pose_manifold.h"
#include "vio/estimator/pose_prior_factor.h"
#include "vio/estimator/speed_bias_prior_factor.h"
#include "vio/estimator/stereo_factor.h"
#include "vio/marginalization/marginalizer.h"

namespace vio {
namespace {
constexpr double kNoAccelThreshold = std::numeric_limits<double>::infinity();

// True when the residual and its Jacobians evaluate to finite values at the
// current point.
bool EvaluatesFinitely(const ceres::Problem& problem, ceres::ResidualBlockId id) {
  const ceres::CostFunction* f = problem.GetCostFunctionForResidualBlock(id);
  std::vector<double> residuals(static_cast<size_t>(f->num_residuals()));
  std::vector<std::vector<double>> jacobian_storage;
  std::vector<double*> jacobians;
  for (const int size : f->parameter_block_sizes()) {
    jacobian_storage.emplace_back(static_cast<size_t>(size * f->num_residuals()));
    jacobians.push_back(jacobian_storage.back().data());
  }
  double cost = 0.0;
  if (!problem.EvaluateResidualBlock(id, true, &cost, residuals.data(), jacobians.data())) return false;
  const auto finite = [](const std::vector<double>& v) {
    return std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); });
  };
  return std::isfinite(cost) && finite(residuals) && std::all_of(jacobian_storage.begin(), jacobian_storage.end(), finite);
}

}  // namespace

void State::SetPose(const Eigen::Vector3d& p_w_b, const Eigen::Quaterniond& q_w_b) {
  const Eigen::Quaterniond q = q_w_b.normalized();
  pose[0] = p_w_b.x(); pose[1] = p_w_b.y(); pose[2] = p_w_b.z();
  pose[3] = q.x(); pose[4] = q.y(); pose[5] = q.z(); pose[6] = q.w();
}

void State::SetSpeedBias(const Eigen::Vector3d& v_w_b, const Eigen::Vector3d& b_g,
                         const Eigen::Vector3d& b_a) {
  Eigen::Map<Eigen::Matrix<double, 9, 1>> sb(speed_bias);
  sb << v_w_b, b_g, b_a;
}

Window::Window(const ModelOptions& model, const RectifiedStereo& stereo)
    : model_(model), stereo_(stereo), pose_manifold_(std::make_unique<PoseManifold>()) {
  if (model_.huber_px > 0) loss_ = std::make_unique<ceres::HuberLoss>(model_.huber_px);
  ceres::Problem::Options options;
  options.enable_fast_removal = true;
  options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_ = std::make_unique<ceres::Problem>(options);
}

Window::~Window() = default;

State& Window::state(StateId id) {
  auto it = states_.find(id);
  CHECK(it != states_.end()) << "no state " << id.value << " in the window";
  return it->second;
}

const State& Window::state(StateId id) const {
  auto it = states_.find(id);
  CHECK(it != states_.end()) << "no state " << id.value << " in the window";
  return it->second;
}

const Landmark& Window::landmark(LandmarkId id) const {
  auto it = landmarks_.find(id);
  CHECK(it != landmarks_.end()) << "no landmark " << id.value << " in the window";
  return it->second;
}

State& Window::AddState(StateId id, Timestamp t_ns) {
  CHECK(!HasState(id)) << "state " << id.value << " added twice";
  State& s = states_[id];
  s.id = id;
  s.t_ns = t_ns;
  problem_->AddParameterBlock(s.pose, kPoseSize, pose_manifold_.get());
  problem_->AddParameterBlock(s.speed_bias, kSpeedBiasSize);
  return s;
}

void Window::AddImuFactor(StateId from, StateId to, ImuPreintegration preintegration) {
  CHECK(HasState(from) && HasState(to)) << "IMU factor between unknown states";
  CHECK(imu_edges_.count(to) == 0) << "state " << to.value << " already has an incoming IMU factor";
  ImuEdge& edge = imu_edges_.emplace(to, ImuEdge{from, to, std::move(preintegration)}).first->second;
  AddImuResidual(edge);
}

void Window::AddImuResidual(ImuEdge& edge) {
  State& a = state(edge.from);
  State& b = state(edge.to);
  const Eigen::Vector3d g_w(0, 0, -model_.gravity);
  edge.residual = problem_->AddResidualBlock(ImuFactor::Create(edge.preintegration, g_w), nullptr,
                                             a.pose, a.speed_bias, b.pose, b.speed_bias);
}

void Window::AddStatePrior(StateId id, const StatePrior& prior) {
  State& s = state(id);
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> covariance(prior.pose_covariance);
  CHECK(covariance.info() == Eigen::Success) << "state prior covariance is not positive definite";
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> information(
      covariance.solve(Eigen::Matrix<double, 6, 6>::Identity()));
  CHECK(information.info() == Eigen::Success) << "state prior information is not positive definite";
  const Eigen::Matrix<double, 6, 6> sqrt_information = information.matrixU();
  Prior pose_prior{problem_->AddResidualBlock(PosePriorFactor::Create(s.p_w_b(), s.q_w_b(), sqrt_information),
                                              nullptr, s.pose),
                   {s.pose}};
  const Eigen::Matrix<double, 9, 1> sigma = prior.speed_bias_sigma;
  Prior sb_prior{problem_->AddResidualBlock(
                     SpeedBiasPriorFactor::Create(Eigen::Map<const Eigen::Matrix<double, 9, 1>>(s.speed_bias),
                                                  sigma.cwiseInverse().asDiagonal().toDenseMatrix()),
                     nullptr, s.speed_bias),
                 {s.speed_bias}};
  priors_.push_back(pose_prior);
  priors_.push_back(sb_prior);
}

Landmark& Window::AddLandmark(LandmarkId id, const Eigen::Vector3d& p_w) {
  CHECK(!HasLandmark(id)) << "landmark " << id.value << " added twice";
  Landmark& l = landmarks_[id];
  l.id = id;
  Eigen::Map<Eigen::Vector3d>(l.p_w) = p_w;
  problem_->AddParameterBlock(l.p_w, kLandmarkSize);
  return l;
}

void Window::AddObservation(StateId state_id, LandmarkId landmark_id, const Eigen::Vector3d& z_px) {
  State& s = state(state_id);
  auto it = landmarks_.find(landmark_id);
  CHECK(it != landmarks_.end()) << "observation of unknown landmark " << landmark_id.value;
  const ObservationKey key{state_id, landmark_id};
  CHECK(observations_.count(key) == 0) << "landmark " << landmark_id.value << " observed twice in state "
                                      << state_id.value;
  ceres::ResidualBlockId residual = problem_->AddResidualBlock(
      StereoFactor::Create(z_px, stereo_, model_.pixel_sigma), loss_.get(), s.pose, it->second.p_w);
  observations_[key] = Observation{z_px, residual};
  it->second.observed_from.insert(state_id);
}

std::set<const double*> Window::BlocksInPriors() const {
  std::set<const double*> in_prior;
  for (const Prior& prior : priors_) in_prior.insert(prior.blocks.begin(), prior.blocks.end());
  return in_prior;
}

std::vector<ceres::ResidualBlockId> Window::ResidualOrder() const {
  std::vector<ceres::ResidualBlockId> order;
  order.reserve(static_cast<size_t>(problem_->NumResidualBlocks()));
  for (const Prior& prior : priors_) order.push_back(prior.residual);
  for (const auto& [to, edge] : imu_edges_) order.push_back(edge.residual);
  for (const auto& [key, observation] : observations_) order.push_back(observation.residual);
  CHECK_EQ(static_cast<int>(order.size()), problem_->NumResidualBlocks()) << "a residual block the window does not know";
  return order;
}

GaussNewtonLayout Window::Layout() const {
  const std::set<const double*> in_prior = BlocksInPriors();
  GaussNewtonLayout layout;
  layout.residuals = ResidualOrder();
  const auto variable = [this](const double* block) { return !problem_->IsParameterBlockConstant(block); };
  for (const auto& [id, s] : states_) {
    for (const double* block : {s.pose, s.speed_bias}) {
      if (variable(block)) layout.dense.push_back(const_cast<double*>(block));
    }
  }
  for (const auto& [id, landmark] : landmarks_) {
    if (!variable(landmark.p_w)) continue;
    auto& group = in_prior.count(landmark.p_w) ? layout.dense : layout.eliminated;
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
  const std::set<const double*> in_prior = BlocksInPriors();
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  int group = 1;
  for (const auto& [id, s] : states_) {
    ordering->AddElementToGroup(const_cast<double*>(s.pose), group++);
    ordering->AddElementToGroup(const_cast<double*>(s.speed_bias), group++);
  }
  for (const auto& [id, landmark] : landmarks_) {
    const bool eliminated = in_prior.count(landmark.p_w) == 0;
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

SolveReport Window::GaussNewton(int max_steps, bool until_converged, const SolverOptions& options) {
  SolveReport report;
  const GaussNewtonLayout layout = Layout();
  for (int k = 0; k < max_steps; ++k) {
    const GaussNewtonStep step = TakeGaussNewtonStep(problem_.get(), layout);
    if (k == 0) report.initial_cost = report.final_cost = step.cost;
    if (!step.ok) {
      report.usable = false;
      ++health_.failed_solves;
      break;
    }
    ++report.iterations;
    double cost = 0;
    if (!EvaluateCost(problem_.get(), layout, &cost)) {
      report.usable = false;
      ++health_.failed_solves;
      break;
    }
    report.final_cost = cost;
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
  ceres::Solver::Summary summary;
  ceres::Solve(solver, problem_.get(), &summary);
  SolveReport report;
  report.iterations = static_cast<int>(summary.iterations.size());
  report.initial_cost = summary.initial_cost;
  report.final_cost = summary.final_cost;
  report.usable = summary.IsSolutionUsable();
  report.converged = summary.termination_type == ceres::CONVERGENCE;
  if (!report.usable) ++health_.failed_solves;
  return report;
}

void Window::SetStateConstant(StateId id, bool constant) {
  State& s = state(id);
  for (double* block : {s.pose, s.speed_bias}) {
    if (constant) {
      problem_->SetParameterBlockConstant(block);
    } else {
      problem_->SetParameterBlockVariable(block);
    }
  }
}

void Window::SetLandmarkConstant(LandmarkId id, bool constant) {
  auto it = landmarks_.find(id);
  CHECK(it != landmarks_.end()) << "no landmark " << id.value << " in the window";
  if (constant) {
    problem_->SetParameterBlockConstant(it->second.p_w);
  } else {
    problem_->SetParameterBlockVariable(it->second.p_w);
  }
}

bool Window::IsStateConstant(StateId id) const { return problem_->IsParameterBlockConstant(state(id).pose); }

int Window::RefreshImuFactors(double gyro_bias_threshold) {
  int refreshed = 0;
  for (auto& [to, edge] : imu_edges_) {
    const State& from = state(edge.from);
    const ImuBias bias{from.gyro_bias(), from.accel_bias()};
    // delta_v and delta_p are linear in the accelerometer bias: the first-order
    // correction is exact there, so only the gyro bias triggers.
    if (!edge.preintegration.NeedsReintegration(bias, gyro_bias_threshold, kNoAccelThreshold)) continue;
    problem_->RemoveResidualBlock(edge.residual);
    edge.preintegration.Reintegrate(bias);
    AddImuResidual(edge);
    ++refreshed;
  }
  return refreshed;
}

void Window::Marginalize(const std::vector<StateId>& state_ids, const std::vector<LandmarkId>& landmark_ids) {
  std::vector<double*> blocks;
  for (StateId id : state_ids) {
    State& s = state(id);
    blocks.push_back(s.pose);
    blocks.push_back(s.speed_bias);
  }
  for (LandmarkId id : landmark_ids) {
    auto it = landmarks_.find(id);
    CHECK(it != landmarks_.end()) << "marginalizing unknown landmark " << id.value;
    blocks.push_back(it->second.p_w);
  }
  if (blocks.empty()) return;
  marginalization::MarginalizationOptions options;
  options.residual_order = ResidualOrder();
  std::set<const double*> removed(blocks.begin(), blocks.end());
  ForgetResidualsOf(removed);
  const std::set<ceres::ResidualBlockId> dropped = DropUnevaluableResiduals(blocks);
  auto& order = options.residual_order;
  order.erase(std::remove_if(order.begin(), order.end(), [&](ceres::ResidualBlockId id) { return dropped.count(id) > 0; }),
              order.end());
  ceres::ResidualBlockId prior = marginalization::MarginalizeBlocks(problem_.get(), blocks, options);
  if (prior != nullptr) {
    std::vector<double*> kept;
    problem_->GetParameterBlocksForResidualBlock(prior, &kept);
    priors_.push_back(Prior{prior, {kept.begin(), kept.end()}});
  }
  for (StateId id : state_ids) RemoveStateBookkeeping(id);
  for (LandmarkId id : landmark_ids) landmarks_.erase(id);
  removals_.marginalized_states.insert(removals_.marginalized_states.end(), state_ids.begin(), state_ids.end());
  removals_.marginalized_landmarks.insert(removals_.marginalized_landmarks.end(), landmark_ids.begin(),
                                          landmark_ids.end());
}

// Drops the bookkeeping of every residual that touches a removed block; the
// residual blocks themselves go with their parameter blocks.
void Window::ForgetResidualsOf(const std::set<const double*>& removed) {
  for (auto it = observations_.begin(); it != observations_.end();) {
    const auto& [state_id, landmark_id] = it->first;
    const bool gone = removed.count(states_.at(state_id).pose) ||
                      removed.count(landmarks_.at(landmark_id).p_w);
    if (gone) {
      landmarks_.at(landmark_id).observed_from.erase(state_id);
      it = observations_.erase(it);
    } else {
      ++it;
    }
  }
  for (auto it = imu_edges_.begin(); it != imu_edges_.end();) {
    const bool gone = removed.count(states_.at(it->second.from).pose) || removed.count(states_.at(it->first).pose);
    it = gone ? imu_edges_.erase(it) : std::next(it);
  }
  for (auto it = priors_.begin(); it != priors_.end();) {
    bool gone = false;
    for (const double* b : it->blocks) gone = gone || removed.count(b) > 0;
    it = gone ? priors_.erase(it) : std::next(it);
  }
}

// A residual that does not evaluate at the current point (a landmark at or
// behind a camera, a non-finite value) would make the whole marginalization
// fail: it is dropped with a warning instead. Bookkeeping is already gone.
std::set<ceres::ResidualBlockId> Window::DropUnevaluableResiduals(const std::vector<double*>& blocks) {
  std::set<ceres::ResidualBlockId> checked;
  std::set<ceres::ResidualBlockId> dropped;
  for (double* block : blocks) {
    std::vector<ceres::ResidualBlockId> residuals;
    problem_->GetResidualBlocksForParameterBlock(block, &residuals);
    for (ceres::ResidualBlockId id : residuals) {
      if (!checked.insert(id).second || EvaluatesFinitely(*problem_, id)) continue;
      LOG(WARNING) << "marginalization: dropped a residual of "
                   << problem_->GetCostFunctionForResidualBlock(id)->num_residuals()
                   << " rows that does not evaluate finitely at the current estimate";
      problem_->RemoveResidualBlock(id);
      dropped.insert(id);
      ++health_.dropped_residuals;
    }
  }
  return dropped;
}

void Window::RemoveStateBookkeeping(StateId id) { states_.erase(id); }

void Window::DropObservation(StateId state_id, LandmarkId landmark_id) {
  auto it = observations_.find({state_id, landmark_id});
  CHECK(it != observations_.end()) << "no observation of " << landmark_id.value << " in " << state_id.value;
  problem_->RemoveResidualBlock(it->second.residual);
  landmarks_.at(landmark_id).observed_from.erase(state_id);
  observations_.erase(it);
}

void Window::DropLandmark(LandmarkId landmark_id) {
  auto it = landmarks_.find(landmark_id);
  CHECK(it != landmarks_.end()) << "dropping unknown landmark " << landmark_id.value;
  std::set<const double*> removed{it->second.p_w};
  ForgetResidualsOf(removed);
  problem_->RemoveParameterBlock(it->second.p_w);
  landmarks_.erase(landmark_id);
  removals_.dropped_landmarks.push_back(landmark_id);
}

bool Window::IsInPrior(StateId id) const {
  const State& s = state(id);
  for (const Prior& prior : priors_) {
    for (const double* block : prior.blocks) {
      if (block == s.pose || block == s.speed_bias) return true;
    }
  }
  return false;
}

void Window::DropState(StateId id) {
  CHECK(!IsInPrior(id)) << "state " << id.value << " is in a prior: marginalize it instead";
  auto incoming = imu_edges_.find(id);
  auto outgoing = std::find_if(imu_edges_.begin(), imu_edges_.end(), [&](const auto& e) { return e.second.from == id; });
  CHECK(incoming != imu_edges_.end() && outgoing != imu_edges_.end())
      << "state " << id.value << " is not between two others";
  std::vector<LandmarkId> seen;
  for (const auto& [key, observation] : observations_) {
    if (key.first == id) seen.push_back(key.second);
  }
  for (LandmarkId landmark_id : seen) {
    DropObservation(id, landmark_id);
    if (landmarks_.at(landmark_id).observed_from.empty()) DropLandmark(landmark_id);
  }
  ImuEdge merged{incoming->second.from, outgoing->first, incoming->second.preintegration};
  merged.preintegration.Append(outgoing->second.preintegration);
  imu_edges_.erase(outgoing);
  imu_edges_.erase(incoming);
  State& s = state(id);
  problem_->RemoveParameterBlock(s.pose);
  problem_->RemoveParameterBlock(s.speed_bias);
  states_.erase(id);
  removals_.dropped_states.push_back(id);
  ImuEdge& edge = imu_edges_.emplace(merged.to, std::move(merged)).first->second;
  AddImuResidual(edge);
}

double Window::ObservationError(StateId state_id, LandmarkId landmark_id) const {
  auto it = observations_.find({state_id, landmark_id});
  CHECK(it != observations_.end()) << "no observation of " << landmark_id.value << " in " << state_id.value;
  return WhitenedError(state_id, landmark_id, it->second.z_px);
}

double Window::WhitenedError(StateId state_id, LandmarkId landmark_id, const Eigen::Vector3d& z_px) const {
  const State& s = state(state_id);
  const Landmark& l = landmark(landmark_id);
  double residual[3];
  const double* params[2] = {s.pose, l.p_w};
  std::unique_ptr<ceres::CostFunction> f(StereoFactor::Create(z_px, stereo_, model_.pixel_sigma));
  if (!f->Evaluate(params, residual, nullptr)) return std::numeric_limits<double>::infinity();
  const double error = Eigen::Map<Eigen::Vector3d>(residual).norm();
  return std::isfinite(error) ? error : std::numeric_limits<double>::infinity();
}

}  // namespace vio
