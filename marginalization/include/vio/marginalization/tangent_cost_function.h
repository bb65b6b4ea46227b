#pragma once
// A cost function that also gives its Jacobians on the tangent spaces of its
// blocks (pose: [dp, dtheta] as in the estimator's pose_manifold.h; Euclidean
// blocks: the ambient Jacobian itself). Ceres wants ambient Jacobians and
// multiplies them by each manifold's PlusJacobian; the estimator's factors
// compute the tangent Jacobian first and map it to the ambient one, so the
// assembly that works on tangents (BlockSystem, block_system.h) asks for it
// directly and skips that round trip. Both agree: ambient * PlusJacobian =
// tangent (the manifold's MinusJacobian * PlusJacobian = I).
namespace vio::marginalization {

class TangentCostFunction {
 public:
  virtual ~TangentCostFunction() = default;
  /// As ceres::CostFunction::Evaluate, with jacobians[i] (when not null)
  /// rows x TangentSize of block i, row-major.
  virtual bool EvaluateOnTangents(double const* const* parameters, double* residuals,
                                  double** jacobians) const = 0;
};

}  // namespace vio::marginalization
