#pragma once
// Batch's frozen observations: a state held constant for good (it left
// batch's active window) contributes to each landmark it sees a cost of that
// landmark alone. Summarized once, when the state freezes, as the quadratic
// model Ceres' Levenberg-Marquardt builds of those residuals there (robust
// loss applied: cost, gradient and Gauss-Newton Hessian), the periodic solves
// of the recent states need not copy and evaluate every such observation
// again (Window::SolveSparse(options, frozen)). The final solve uses the
// residuals themselves.
#include <map>

#include <Eigen/Core>

#include "vio/estimator/types.h"

namespace vio {

/// The model m(p) = 1/2 d^T H d + b^T d + c, d = p - reference, of a landmark's
/// frozen observations, each taken at the landmark's value when its state froze.
struct LandmarkSummary {
  Eigen::Vector3d reference = Eigen::Vector3d::Zero();     ///< [m], the first linearization point
  Eigen::Matrix3d information = Eigen::Matrix3d::Zero();   ///< H [1/m^2]
  Eigen::Vector3d linear = Eigen::Vector3d::Zero();        ///< b [1/m]
  double constant = 0;                                     ///< c, the cost at the reference
  int observations = 0;
};

/// One observation's part of a summary (what AddToSummary added), kept to take it out again
/// (the smoother frees a held state).
struct SummarizedObservation {
  LandmarkId landmark;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();  ///< [m], the landmark where it was taken
  double f = 0;
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
};

struct FrozenObservations {
  std::map<LandmarkId, LandmarkSummary> landmarks;
  int skipped = 0;  ///< observations that did not evaluate when their state froze (left out)
};

/// Adds one observation's cost f, gradient g and Gauss-Newton Hessian h (over the landmark's
/// position) taken at `p` to `summary`.
void AddToSummary(const Eigen::Vector3d& p, double f, const Eigen::Vector3d& g, const Eigen::Matrix3d& h,
                  LandmarkSummary& summary);

/// Takes `observation` out of its landmark's summary in `frozen` (the exact inverse of
/// AddToSummary with the same arguments); a summary left with no observation is erased.
void RemoveFromSummary(const SummarizedObservation& observation, FrozenObservations& frozen);

}  // namespace vio
