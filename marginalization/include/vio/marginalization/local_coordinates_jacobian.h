#pragma once
// An optional capability a ceres::Manifold can add so that a
// MarginalizationPrior differentiates its local coordinates x ⊟ x0 exactly.
//
// ceres::Manifold only provides MinusJacobian(x) = D_1 Minus(y, x) at y == x.
// A prior needs the derivative of Minus(x ⊞ delta, x0) at delta = 0 for any x,
// in particular x != x0. A manifold that knows it in closed form (e.g. a Lie
// group: the inverse of the right/left Jacobian of the logarithm) inherits
// from this interface as well as from ceres::Manifold:
//
//   class PoseManifold : public ceres::Manifold,
//                        public vio::marginalization::LocalCoordinatesJacobian {...};
//
// Manifolds without it get a central-difference derivative built from their
// own Plus() and Minus() (see MarginalizationPrior).

namespace vio::marginalization {

class LocalCoordinatesJacobian {
 public:
  virtual ~LocalCoordinatesJacobian() = default;

  /// jacobian = d Minus(Plus(x, delta), x0) / d delta at delta = 0.
  /// x and x0 are AmbientSize() vectors; jacobian is a row-major
  /// TangentSize() x TangentSize() matrix. Returns false on failure.
  virtual bool MinusTangentJacobian(const double* x, const double* x0, double* jacobian) const = 0;
};

}  // namespace vio::marginalization
