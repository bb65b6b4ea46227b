// Window's third operation, marginalization (paper §2.3): the residuals of what
// leaves, in id order and with their blocks' keys, folded into one prior on the
// blocks they touch that stay (vio_marginalization), whose keys the window keeps.
#include <algorithm>
#include <cstdint>
#include <exception>
#include <memory>
#include <tuple>
#include <unordered_set>
#include <utility>

#include <glog/logging.h>

#include "keyed_residuals.h"
#include "vio/estimator/window.h"
#include "vio/marginalization/marginalizer.h"

namespace vio {
namespace {

// A kept block's place in a marginalization's columns: speed/bias blocks, then poses, by state id;
// the time offset; then the others (landmarks, extrinsics), all equal.
std::tuple<int, std::int64_t> KeptColumnRank(const BlockKey& key) {
  switch (key.kind) {
    case BlockKey::Kind::kSpeedBias:
      return {0, key.id};
    case BlockKey::Kind::kPose:
      return {1, key.id};
    case BlockKey::Kind::kTimeOffset:
      return {2, 0};
    default:
      return {3, 0};
  }
}

}  // namespace

void Window::Marginalize(const std::vector<StateId>& state_ids, const std::vector<LandmarkId>& landmark_ids) {
  std::vector<double*> blocks = Blocks(state_ids, landmark_ids);
  if (blocks.empty()) return;
  const Leaving leaving = LeavingOf(state_ids, landmark_ids);
  const LeavingKeys keys = LeavingKeysOf(leaving);
  KeyedResiduals residuals = ResidualOrderOf(leaving, keys);
  ForgetResidualsOf(leaving, keys);
  std::vector<BlockKey> kept_order;
  const ceres::ResidualBlockId prior = MarginalizeEvaluable(blocks, std::move(residuals), leaving, &kept_order);
  last_prior_rank_deficient_ = false;
  if (prior != nullptr) KeepPrior(prior, kept_order);
  for (StateId id : state_ids) {
    removals_.leaving_states.push_back(states_.at(id));
    RemoveStateBookkeeping(id);
  }
  for (LandmarkId id : landmark_ids) {
    removals_.leaving_landmarks.emplace_back(id, landmarks_.at(id).position());
    RemoveLandmarkBookkeeping(id);
  }
  removals_.marginalized_states.insert(removals_.marginalized_states.end(), state_ids.begin(), state_ids.end());
  removals_.marginalized_landmarks.insert(removals_.marginalized_landmarks.end(), landmark_ids.begin(),
                                          landmark_ids.end());
}

Window::Leaving Window::LeavingOf(const std::vector<StateId>& states, const std::vector<LandmarkId>& landmarks) {
  return {{states.begin(), states.end()}, {landmarks.begin(), landmarks.end()}, {}};
}

bool Window::Leaving::Has(const BlockKey& key) const {
  switch (key.kind) {
    case BlockKey::Kind::kPose:
    case BlockKey::Kind::kSpeedBias:
      return states.count(StateId(key.id)) > 0;
    case BlockKey::Kind::kLandmark:
      return landmarks.count(LandmarkId(key.id)) > 0;
    default:
      return calibration.count(key) > 0;
  }
}

std::vector<BlockKey> Window::KeptOrderOf(const KeyedResiduals& residuals, const Leaving& leaving) const {
  std::vector<BlockKey> kept;
  std::unordered_set<BlockKey, BlockKeyHash> seen;
  for (const BlockKey& key : residuals.keys) {
    if (!leaving.Has(key) && seen.insert(key).second) kept.push_back(key);
  }
  std::stable_sort(kept.begin(), kept.end(),
                   [](const BlockKey& a, const BlockKey& b) { return KeptColumnRank(a) < KeptColumnRank(b); });
  return kept;
}

marginalization::MarginalizationOptions Window::MarginalizationOptionsOf(const KeyedResiduals& residuals,
                                                                         const Leaving& leaving,
                                                                         std::vector<BlockKey>* kept_order) {
  marginalization::MarginalizationOptions options;
  options.residual_order = residuals.ids;
  options.residual_order_is_exact = true;  // every residual of what leaves, by the window's bookkeeping
  *kept_order = KeptOrderOf(residuals, leaving);
  for (const BlockKey& key : *kept_order) {
    options.kept_order.push_back(BlockOf(key));
    if (first_estimates_) options.first_estimates.push_back(first_estimates_->Find(key));
  }
  if (marginal_system_ == nullptr) {
    marginal_system_ = std::make_unique<marginalization::BlockSystem>(problem_.get(), marginalization::BlockLayout{});
  }
  options.system = marginal_system_.get();
  // Rank-deficient priors come in runs: after one, no unpivoted attempt at the
  // next square root (a whole factorization that would fail its pivot test).
  if (last_prior_rank_deficient_) options.sqrt_method = marginalization::SqrtMethod::kPivotedCholeskyOnly;
  return options;
}

// The prior's blocks are the kept blocks that are variable, in kept_order's order.
void Window::KeepPrior(ceres::ResidualBlockId prior, const std::vector<BlockKey>& kept_order) {
  std::vector<double*> kept;
  problem_->GetParameterBlocksForResidualBlock(prior, &kept);
  std::vector<BlockKey> keys;
  keys.reserve(kept.size());
  auto next = kept_order.begin();
  int tangent_dim = 0;
  for (const double* block : kept) {
    while (next != kept_order.end() && BlockOf(*next) != block) ++next;
    CHECK(next != kept_order.end()) << "a marginalization prior on a block outside its Markov blanket";
    keys.push_back(*next++);
    tangent_dim += problem_->ParameterBlockTangentSize(block);
  }
  last_prior_rank_deficient_ = problem_->GetCostFunctionForResidualBlock(prior)->num_residuals() < tangent_dim;
  HoldFirstEstimates(keys);
  priors_.push_back(Prior{prior, std::move(keys)});
}

// Drops the bookkeeping of every residual of what leaves; the residual blocks
// themselves go with their parameter blocks.
void Window::ForgetResidualsOf(const Leaving& leaving) { ForgetResidualsOf(leaving, LeavingKeysOf(leaving)); }

void Window::ForgetResidualsOf(const Leaving& leaving, const LeavingKeys& keys) {
  for (const ObservationKey& key : keys.observations) {
    landmarks_.at(key.second).observed_from.erase(key.first);
    observations_.erase(key);
  }
  for (const ObservationKey& key : keys.anchored) {
    landmarks_.at(key.second).anchored_to.erase(key.first);
    anchored_points_.erase(key);
  }
  for (auto it = imu_edges_.begin(); it != imu_edges_.end();) {
    it = Touches(it->first, it->second, leaving) ? imu_edges_.erase(it) : std::next(it);
  }
  for (auto it = priors_.begin(); it != priors_.end();) {
    it = Touches(*it, leaving) ? priors_.erase(it) : std::next(it);
  }
}

// The marginalization assembles every residual of `blocks` and fails (throws,
// the problem untouched) when one does not evaluate finitely: only then are
// those residuals looked for and dropped, and the marginalization retried.
ceres::ResidualBlockId Window::MarginalizeEvaluable(const std::vector<double*>& blocks, KeyedResiduals residuals,
                                                    const Leaving& leaving, std::vector<BlockKey>* kept_order) {
  try {
    return marginalization::MarginalizeBlocks(problem_.get(), blocks,
                                              MarginalizationOptionsOf(residuals, leaving, kept_order));
  } catch (const std::exception&) {  // a failure that no dropped residual explains throws again below
  }
  DropUnevaluableResiduals(&residuals);
  return marginalization::MarginalizeBlocks(problem_.get(), blocks,
                                            MarginalizationOptionsOf(residuals, leaving, kept_order));
}

}  // namespace vio
