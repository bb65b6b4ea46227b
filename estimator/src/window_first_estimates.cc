// Window's first-estimate Jacobians (model.fej; first_estimates.h): which
// factors are wrapped and which blocks are held.
#include <glog/logging.h>

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

void Window::HoldFirstEstimates(const std::vector<double*>& blocks) {
  if (!first_estimates_) return;
  for (const double* block : blocks) first_estimates_->Hold(KeyOf(block), block, problem_->ParameterBlockSize(block));
}

BlockKey Window::KeyOf(const double* block) const {
  const auto it = block_keys_.find(block);
  CHECK(it != block_keys_.end()) << "a parameter block that is neither a state nor a landmark of the window";
  return it->second;
}

}  // namespace vio
