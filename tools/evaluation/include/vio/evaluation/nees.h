#pragma once
// Consistency of an estimate: the normalized estimation error squared (NEES)
// of every pose against ground truth, with the covariance the estimator
// reported (`vio run --output_covariance`, covariance.csv).
//
// Error frame. The covariance is over the pose tangent of PoseManifold
// (window_covariance.h): [dp (world), dtheta (body)] with the truth x =
// x_hat ⊞ d. The error of an aligned estimate is therefore
//   e = x_gt ⊟ x_hat = [p_gt - p_hat, Log(R_hat^T R_gt)],
// and the covariance is carried through the same alignment as the estimate
// (p_hat <- s R_a p_hat + t_a, R_hat <- R_a R_hat): the world-frame position
// block turns with s R_a, the body-frame rotation block does not change:
//   Sigma' = T Sigma T^T, T = blockdiag(s R_a, I).
// NEES: position e_p^T Sigma_pp'^-1 e_p (3 dof), orientation (3 dof), pose
// e^T Sigma'^-1 e (6 dof). A consistent estimator has mean NEES = dof.
//
// Gauge. The estimator fixes the unobservable directions (position, yaw) with
// its prior on the first state, so its covariance is that of the error in the
// frame where the first state sits on that prior's mean: the estimate is
// aligned at its first pose (AlignAtFirstPose: position and yaw for posyaw,
// the whole pose for se3/sim3, nothing for none), not by a fit over the whole
// trajectory. A fit is another gauge: it moves the error of the first frames
// (whose covariance is the prior's, 1 mm / 1 mrad) by the average drift and
// takes the drift out of the later ones, so NEES came out too large at the
// start and too small in flight (a 60 s synthetic flight, SWF(10): 24.8 in the
// first 10 s with the fit, 7.7 anchored).
#include <string>
#include <vector>

#include <Eigen/Core>

#include "vio/evaluation/trajectory_eval.h"

namespace vio::tools {

/// One row of covariance.csv: the pose covariance of one frame.
struct PoseCovariance {
  Timestamp t_ns = 0;
  Eigen::Matrix<double, 6, 6> pose;  ///< over [dp (world, m), dtheta (body, rad)]
};

/// Reads covariance.csv (see tools/cli run_output.h: #t_ns, 21 upper-triangle
/// entries of the pose covariance, 9 variances). Throws DatasetError naming the
/// file and line on a bad row, non-increasing stamps or a covariance that is
/// not symmetric positive definite.
std::vector<PoseCovariance> ReadCovarianceCsv(const std::string& path);

/// NEES of one frame.
struct NeesSample {
  Timestamp t_ns = 0;
  double position = 0;     ///< 3 dof
  double orientation = 0;  ///< 3 dof
  double pose = 0;         ///< 6 dof
};

/// NEES of every frame with both a covariance and ground truth, and their means.
struct NeesResult {
  std::vector<NeesSample> samples;
  double mean_position = 0;
  double mean_orientation = 0;
  double mean_pose = 0;
  int num_without_covariance = 0;  ///< aligned poses without a covariance row (not counted)
};

/// NEES of an aligned trajectory (ApplyAlignment with `alignment`) against
/// the covariances (matched by exact stamp).
NeesResult ComputeNees(const AssociatedTrajectory& aligned, const AlignmentResult& alignment,
                       const std::vector<PoseCovariance>& covariances);

/// Associates, aligns at the first pose along the directions of
/// `options.alignment` (AlignAtFirstPose, see "Gauge" above) and computes the NEES.
NeesResult EvaluateNees(const std::vector<GroundTruthState>& estimate,
                        const std::vector<GroundTruthState>& groundtruth,
                        const std::vector<PoseCovariance>& covariances, const EvaluationOptions& options);

/// nees.csv: "#t_ns,nees_position,nees_orientation,nees_pose", one row per sample.
void WriteNeesCsv(const NeesResult& nees, const std::string& path);
/// {"frames": n, "position": .., "orientation": .., "pose": ..} (means).
std::string NeesJson(const NeesResult& nees);

/// Two-sided 95% interval of the mean NEES of `num_runs` independent
/// consistent runs at one instant: chi2(num_runs * dof) / num_runs, quantiles
/// 2.5% and 97.5% by the Wilson-Hilferty approximation (relative error below
/// 1e-3 at 120 dof = 20 runs of 6 dof; 3% at 6 dof).
struct ChiSquareBounds {
  double lower = 0;
  double upper = 0;
};
ChiSquareBounds AneesBounds95(int dof, int num_runs);

}  // namespace vio::tools
