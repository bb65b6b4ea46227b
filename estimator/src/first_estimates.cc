#include "vio/estimator/first_estimates.h"

#include <Eigen/Core>
#include <glog/logging.h>

namespace vio {

using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

void FirstEstimates::Hold(const BlockKey& key, const double* values, int size) {
  if (values_.count(key) == 0) values_[key].assign(values, values + size);
}

const double* FirstEstimates::Find(const BlockKey& key) const {
  const auto it = values_.find(key);
  return it == values_.end() ? nullptr : it->second.data();
}

FejCostFunction::FejCostFunction(ceres::CostFunction* wrapped, std::vector<Parameter> parameters,
                                 std::shared_ptr<const FirstEstimates> first_estimates)
    : wrapped_(wrapped), parameters_(std::move(parameters)), first_estimates_(std::move(first_estimates)) {
  CHECK_EQ(parameters_.size(), wrapped_->parameter_block_sizes().size()) << "one key per parameter block";
  set_num_residuals(wrapped_->num_residuals());
  *mutable_parameter_block_sizes() = wrapped_->parameter_block_sizes();
}

bool FejCostFunction::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  std::vector<const double*> at(parameters, parameters + parameters_.size());
  bool any_held = false;
  for (size_t i = 0; i < parameters_.size(); ++i) {
    if (const double* first = first_estimates_->Find(parameters_[i].key)) {
      at[i] = first;
      any_held = true;
    }
  }
  if (jacobians == nullptr || !any_held) return wrapped_->Evaluate(parameters, residuals, jacobians);
  if (!wrapped_->Evaluate(parameters, residuals, nullptr)) return false;
  std::vector<double> residuals_at_first(static_cast<size_t>(num_residuals()));
  if (!wrapped_->Evaluate(at.data(), residuals_at_first.data(), jacobians)) return false;
  for (size_t i = 0; i < parameters_.size(); ++i) {
    const ceres::Manifold* manifold = parameters_[i].manifold;
    if (jacobians[i] == nullptr || manifold == nullptr || at[i] == parameters[i]) continue;
    const int ambient = manifold->AmbientSize(), tangent = manifold->TangentSize();
    RowMajorMatrix plus_at_first(ambient, tangent), minus_at_current(tangent, ambient);
    if (!manifold->PlusJacobian(at[i], plus_at_first.data()) ||
        !manifold->MinusJacobian(parameters[i], minus_at_current.data())) {
      return false;
    }
    Eigen::Map<RowMajorMatrix> J(jacobians[i], num_residuals(), ambient);
    const RowMajorMatrix tangent_jacobian = J * plus_at_first;
    J = tangent_jacobian * minus_at_current;
  }
  return true;
}

}  // namespace vio
