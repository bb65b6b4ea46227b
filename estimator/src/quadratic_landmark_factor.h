#pragma once
// A landmark's frozen observations in a solve: the residual of their summary
// (frozen_observations.h), 1/2 |r|^2 = m(p).
#include <memory>

#include <ceres/cost_function.h>

#include "vio/estimator/frozen_observations.h"

namespace vio {

/// r = [R (p - reference) + d; e] over the landmark's position, R^T R = H,
/// R^T d = b, 1/2 e^2 = c - 1/2 d^T d (from H's eigen-decomposition; directions
/// of H below 1e-12 of its largest eigenvalue dropped, with their part of b).
std::unique_ptr<ceres::CostFunction> QuadraticLandmarkFactor(const LandmarkSummary& summary);

}  // namespace vio
