#include "vio/estimator/window.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <limits>
#include <utility>

#include <glog/logging.h>

#include "keyed_residuals.h"
#include "vio/estimator/imu_factor.h"
#include "vio/estimator/pose_manifold.h"
#include "vio/estimator/pose_prior_factor.h"
#include "vio/estimator/speed_bias_prior_factor.h"
#include "vio/estimator/stereo_factor.h"
#include "vio/marginalization/marginalization_prior.h"
#include "vio/marginalization/marginalizer.h"

namespace vio {
namespace {
constexpr double kNoAccelThreshold = std::numeric_limits<double>::infinity();

// True when the residual and its Jacobians evaluate to finite values at the
// current point.
bool EvaluatesFinitely(const ceres::Problem& problem, ceres::ResidualBlockId id) {
  const ceres::CostFunction* f = problem.GetCostFunctionForResidualBlock(id);
  // A prior's Jacobian (its finite Jp times the manifolds' finite tangent
  // maps) is finite wherever its residual is: its residual alone is checked,
  // which spares forming its dense n x n Jacobian.
  const bool residual_only = dynamic_cast<const marginalization::MarginalizationPrior*>(f) != nullptr;
  std::vector<double> residuals(static_cast<size_t>(f->num_residuals()));
  std::vector<std::vector<double>> jacobian_storage;
  std::vector<double*> jacobians;
  std::vector<double*> blocks;
  problem.GetParameterBlocksForResidualBlock(id, &blocks);
  for (size_t i = 0; i < blocks.size() && !residual_only; ++i) {
    // Ceres gives no Jacobian on a constant block (a fixed keyframe of the local map).
    if (problem.IsParameterBlockConstant(blocks[i])) {
      jacobians.push_back(nullptr);
      continue;
    }
    jacobian_storage.emplace_back(static_cast<size_t>(f->parameter_block_sizes()[i] * f->num_residuals()));
    jacobians.push_back(jacobian_storage.back().data());
  }
  double cost = 0.0;
  if (!problem.EvaluateResidualBlock(id, true, &cost, residuals.data(), residual_only ? nullptr : jacobians.data())) {
    return false;
  }
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

Window::Window(const ModelOptions& model, const RectifiedStereo& stereo, ResidualIndex index)
    : model_(model),
      stereo_(std::make_shared<const RectifiedStereo>(stereo)),
      pose_manifold_(std::make_unique<PoseManifold>()) {
  if (model_.huber_px > 0) loss_ = std::make_unique<ceres::HuberLoss>(model_.huber_px);
  ceres::Problem::Options options;
  options.enable_fast_removal = index == ResidualIndex::kPerBlock;
  options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  // Ceres' per-residual checks (a sorted copy of the blocks for duplicates, block sizes, aliasing of a new
  // block's memory) cannot fail here: every block is a State's, Landmark's or calibration's own array, added
  // with its size once, and each factor takes distinct ones.
  options.disable_all_safety_checks = true;
  problem_ = std::make_unique<ceres::Problem>(options);
  if (model_.fej) first_estimates_ = std::make_shared<FirstEstimates>();
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
  variable_states_.insert(id);
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
  const auto keys = ImuKeys(a.id, b.id);
  ceres::CostFunction* factor =
      WithFirstEstimates(Wrap(ImuFactor::Create(edge.preintegration, g_w)), {keys.begin(), keys.end()});
  edge.residual = problem_->AddResidualBlock(factor, nullptr, a.pose, a.speed_bias, b.pose, b.speed_bias);
}

void Window::AddStatePrior(StateId id, const StatePrior& prior) {
  State& s = state(id);
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> covariance(prior.pose_covariance);
  CHECK(covariance.info() == Eigen::Success) << "state prior covariance is not positive definite";
  const Eigen::LLT<Eigen::Matrix<double, 6, 6>> information(
      covariance.solve(Eigen::Matrix<double, 6, 6>::Identity()));
  CHECK(information.info() == Eigen::Success) << "state prior information is not positive definite";
  const Eigen::Matrix<double, 6, 6> sqrt_information = information.matrixU();
  HoldFirstEstimates({BlockKey::Pose(id), BlockKey::SpeedBias(id)});
  Prior pose_prior{problem_->AddResidualBlock(
                       WithFirstEstimates(PosePriorFactor::Create(s.p_w_b(), s.q_w_b(), sqrt_information),
                                          {BlockKey::Pose(id)}),
                       nullptr, s.pose),
                   {BlockKey::Pose(id)}};
  const Eigen::Matrix<double, 9, 1> sigma = prior.speed_bias_sigma;
  Prior sb_prior{problem_->AddResidualBlock(
                     WithFirstEstimates(
                         SpeedBiasPriorFactor::Create(Eigen::Map<const Eigen::Matrix<double, 9, 1>>(s.speed_bias),
                                                      sigma.cwiseInverse().asDiagonal().toDenseMatrix()),
                         {BlockKey::SpeedBias(id)}),
                     nullptr, s.speed_bias),
                 {BlockKey::SpeedBias(id)}};
  priors_.push_back(pose_prior);
  priors_.push_back(sb_prior);
}

Landmark& Window::AddLandmark(LandmarkId id, const Eigen::Vector3d& p_w) {
  CHECK(!HasLandmark(id)) << "landmark " << id.value << " added twice";
  Landmark& l = landmarks_[id];
  l.id = id;
  Eigen::Map<Eigen::Vector3d>(l.p_w) = p_w;
  problem_->AddParameterBlock(l.p_w, kLandmarkSize);
  variable_landmarks_.insert(id);
  return l;
}

void Window::AddObservation(StateId state_id, LandmarkId landmark_id, const Eigen::Vector3d& z_px) {
  State& s = state(state_id);
  auto it = landmarks_.find(landmark_id);
  CHECK(it != landmarks_.end()) << "observation of unknown landmark " << landmark_id.value;
  const auto [entry, added] = observations_.try_emplace({state_id, landmark_id});
  CHECK(added) << "landmark " << landmark_id.value << " observed twice in state " << state_id.value;
  // The pose, the landmark, then the calibration blocks in CalibrationBlocks()' order; their keys
  // only for first estimates.
  constexpr int kMostBlocks = 4;
  std::array<double*, kMostBlocks> blocks{s.pose, it->second.p_w};
  int count = 2;
  std::vector<BlockKey> keys;
  if (first_estimates_) {
    const auto point = PointKeys(state_id, landmark_id);
    keys.assign(point.begin(), point.end());
  }
  for (const auto& [block, block_key] : KeyedCalibrationBlocks()) {
    CHECK_LT(count, kMostBlocks) << "more calibration blocks than an observation's factor takes";
    blocks[static_cast<size_t>(count++)] = block;
    if (first_estimates_) keys.push_back(block_key);
  }
  ceres::CostFunction* factor = Wrap(StereoFactorOf(state_id, landmark_id, z_px));
  if (first_estimates_) factor = WithFirstEstimates(factor, std::move(keys));
  const ceres::ResidualBlockId residual = problem_->AddResidualBlock(factor, loss_.get(), blocks.data(), count);
  entry->second = Observation{z_px, residual};
  it->second.observed_from.insert(state_id);
}

std::vector<BlockKey> Window::KeysOf(const std::vector<StateId>& state_ids,
                                     const std::vector<LandmarkId>& landmark_ids) {
  std::vector<BlockKey> keys;
  keys.reserve(2 * state_ids.size() + landmark_ids.size());
  for (StateId id : state_ids) {
    keys.push_back(BlockKey::Pose(id));
    keys.push_back(BlockKey::SpeedBias(id));
  }
  for (LandmarkId id : landmark_ids) keys.push_back(BlockKey::Landmark(id));
  return keys;
}

std::vector<double*> Window::Blocks(const std::vector<StateId>& state_ids,
                                   const std::vector<LandmarkId>& landmark_ids) {
  std::vector<double*> blocks;
  for (const BlockKey& key : KeysOf(state_ids, landmark_ids)) blocks.push_back(BlockOf(key));
  return blocks;
}

double* Window::BlockOf(const BlockKey& key) const {
  switch (key.kind) {
    case BlockKey::Kind::kPose:
      return const_cast<double*>(state(StateId(key.id)).pose);
    case BlockKey::Kind::kSpeedBias:
      return const_cast<double*>(state(StateId(key.id)).speed_bias);
    case BlockKey::Kind::kLandmark:
      return const_cast<double*>(landmark(LandmarkId(key.id)).p_w);
    case BlockKey::Kind::kTimeOffset:
      CHECK(estimates_time_offset()) << "the time offset is not estimated";
      return const_cast<double*>(time_offset_);
    case BlockKey::Kind::kExtrinsics:
      CHECK(estimates_extrinsics()) << "the extrinsics are not estimated";
      return const_cast<double*>(extrinsic_);
  }
  LOG(FATAL) << "a block key of no kind";
}

void Window::AddLinearFactor(const std::vector<StateId>& state_ids, const std::vector<LandmarkId>& landmark_ids,
                             const Eigen::MatrixXd& jacobian, const Eigen::VectorXd& residual) {
  const std::vector<double*> blocks = Blocks(state_ids, landmark_ids);
  std::vector<marginalization::MarginalizationPrior::Block> prior_blocks;
  for (double* block : blocks) {
    const bool pose = problem_->GetManifold(block) != nullptr;
    const int size = problem_->ParameterBlockSize(block);
    prior_blocks.push_back({pose ? pose_manifold_.get() : nullptr, std::vector<double>(block, block + size)});
  }
  auto factor = marginalization::MarginalizationPrior::Create(std::move(prior_blocks), jacobian, residual);
  const ceres::ResidualBlockId id = problem_->AddResidualBlock(Wrap(factor.release()), nullptr, blocks);
  priors_.push_back(Prior{id, KeysOf(state_ids, landmark_ids)});
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
  if (constant) {
    variable_states_.erase(id);
  } else {
    variable_states_.insert(id);
  }
}

void Window::SetLandmarkConstant(LandmarkId id, bool constant) {
  auto it = landmarks_.find(id);
  CHECK(it != landmarks_.end()) << "no landmark " << id.value << " in the window";
  if (constant) {
    problem_->SetParameterBlockConstant(it->second.p_w);
    variable_landmarks_.erase(id);
  } else {
    problem_->SetParameterBlockVariable(it->second.p_w);
    variable_landmarks_.insert(id);
  }
}

bool Window::IsStateConstant(StateId id) const { return problem_->IsParameterBlockConstant(state(id).pose); }

int Window::RefreshImuFactors(double gyro_bias_threshold, StateId first_to) {
  int refreshed = 0;
  for (auto it = imu_edges_.lower_bound(first_to); it != imu_edges_.end(); ++it) {
    ImuEdge& edge = it->second;
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

// A residual that does not evaluate at the current point (a landmark at or
// behind a camera, a non-finite value) would make the whole marginalization
// fail: it is dropped with a warning instead. Bookkeeping is already gone.
void Window::DropUnevaluableResiduals(KeyedResiduals* residuals) {
  KeyedResiduals evaluable;
  for (std::size_t k = 0; k < residuals->size(); ++k) {
    const ceres::ResidualBlockId id = residuals->ids[k];
    if (EvaluatesFinitely(*problem_, id)) {
      evaluable.Add(id, residuals->begin(k), residuals->end(k));
      continue;
    }
    LOG(WARNING) << "marginalization: dropped a residual of "
                 << problem_->GetCostFunctionForResidualBlock(id)->num_residuals()
                 << " rows that does not evaluate finitely at the current estimate";
    problem_->RemoveResidualBlock(id);
    ++health_.dropped_residuals;
  }
  *residuals = std::move(evaluable);
}

std::vector<Window::ObservationKey> Window::UnevaluableObservations() const {
  std::vector<ObservationKey> failing;
  for (const auto& [key, observation] : observations_) {
    if (!EvaluatesFinitely(*problem_, observation.residual)) failing.push_back(key);
  }
  return failing;
}

int Window::DropUnevaluableObservations() {
  const std::vector<ObservationKey> failing = UnevaluableObservations();
  DropOutlierObservations(failing);
  return static_cast<int>(failing.size());
}

void Window::DropOutlierObservations(const std::vector<ObservationKey>& observations) {
  const std::set<LandmarkId> held = LandmarksInPriors();
  for (const auto& [state_id, landmark_id] : observations) {
    DropObservation(state_id, landmark_id);
    ++health_.dropped_observations;
    const Landmark& l = landmarks_.at(landmark_id);
    if (Unconstrained(l) && held.count(landmark_id) == 0) DropLandmark(landmark_id);
  }
}

void Window::RemoveStateBookkeeping(StateId id) {
  variable_states_.erase(id);
  states_.erase(id);
  camera_timing_.erase(id);
}

void Window::RemoveLandmarkBookkeeping(LandmarkId id) {
  variable_landmarks_.erase(id);
  landmarks_.erase(id);
}

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
  ForgetResidualsOf(LeavingOf({}, {landmark_id}));
  removals_.leaving_landmarks.emplace_back(landmark_id, it->second.position());
  problem_->RemoveParameterBlock(it->second.p_w);
  RemoveLandmarkBookkeeping(landmark_id);
  removals_.dropped_landmarks.push_back(landmark_id);
}

bool Window::IsInPrior(StateId id) const {
  CHECK(HasState(id)) << "no state " << id.value << " in the window";
  const auto of_state = [id](const BlockKey& key) { return key.IsOf(id); };
  return std::any_of(priors_.begin(), priors_.end(),
                     [&](const Prior& prior) { return std::any_of(prior.keys.begin(), prior.keys.end(), of_state); });
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
    if (Unconstrained(landmarks_.at(landmark_id))) DropLandmark(landmark_id);
  }
  for (const ObservationKey& key : AnchoredKeysOf(LeavingOf({id}, {}))) {
    problem_->RemoveResidualBlock(anchored_points_.at(key));
    anchored_points_.erase(key);
    landmarks_.at(key.second).anchored_to.erase(id);
    if (Unconstrained(landmarks_.at(key.second))) DropLandmark(key.second);
  }
  ImuEdge merged{incoming->second.from, outgoing->first, incoming->second.preintegration};
  merged.preintegration.Append(outgoing->second.preintegration);
  imu_edges_.erase(outgoing);
  imu_edges_.erase(incoming);
  State& s = state(id);
  removals_.leaving_states.push_back(s);
  problem_->RemoveParameterBlock(s.pose);
  problem_->RemoveParameterBlock(s.speed_bias);
  RemoveStateBookkeeping(id);
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
  if (!StereoFactor::EvaluateAt(estimated_stereo(), z_px, 1.0 / model_.pixel_sigma, params, residual, nullptr,
                                /*on_tangents=*/false)) {
    return std::numeric_limits<double>::infinity();
  }
  const double error = Eigen::Map<Eigen::Vector3d>(residual).norm();
  return std::isfinite(error) ? error : std::numeric_limits<double>::infinity();
}

}  // namespace vio
