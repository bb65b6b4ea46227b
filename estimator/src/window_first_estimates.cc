// Window's first-estimate Jacobians (model.fej; first_estimates.h): which
// factors are wrapped and which blocks are held.
#include "vio/estimator/pose_manifold.h"
#include "vio/estimator/window.h"

namespace vio {

ceres::CostFunction* Window::WithFirstEstimates(ceres::CostFunction* factor, std::vector<BlockKey> keys) const {
  if (!first_estimates_) return factor;
  std::vector<FejCostFunction::Parameter> parameters;
  for (const BlockKey& key : keys) {
    parameters.push_back({key, key.kind == BlockKey::Kind::kPose ? pose_manifold_.get() : nullptr});
  }
  return new FejCostFunction(factor, std::move(parameters), first_estimates_);
}

void Window::HoldFirstEstimates(const std::vector<BlockKey>& keys) {
  if (!first_estimates_) return;
  for (const BlockKey& key : keys) {
    const double* block = BlockOf(key);
    first_estimates_->Hold(key, block, problem_->ParameterBlockSize(block));
  }
}

}  // namespace vio
