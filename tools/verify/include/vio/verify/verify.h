#pragma once
// `vio verify`: the design paper's equivalence theorems (4.3.1-4.3.5 and
// Remark 4.3.2, see vio/marginalization/equivalence.h) checked on random
// problems of two kinds, and reported as a table:
//
//   linear     linear-Gaussian problems (vio_marginalization's generator);
//   nonlinear  small SE3 problems: body poses on vio::PoseManifold with body
//              velocities, 3D landmarks seen by the rectified stereo camera
//              (vio::StereoFactor), a constant-body-velocity motion model
//              (VerifyMotionResidual, autodiff), all linearized at the same
//              point for both forms. The filter side gets the analytic
//              motion Jacobian G and the analytic Jacobians of stereo
//              triangulation (the EKF's inverse measurement map ℓ); the cost
//              side gets the factors' own Jacobians.
//
// Per theorem and kind: the largest relative deviation of means and of
// covariances over the trials, and the negative controls (wrong filters that
// must disagree).
#include <string>
#include <vector>

#include "vio/marginalization/equivalence.h"

namespace vio::tools {

/// Sizes of the nonlinear problems.
struct NonlinearProblemSizes {
  /// p (EKF), |S_f| (MSCKF), in [1, 50]; p' = max(1, p / 2). The MSCKF
  /// update is dense in its measurements (up to 3 p n rows): at 40 x 20 one
  /// trial takes seconds.
  int num_landmarks = 6;
  int num_poses = 4;  ///< n, MSCKF poses, in [2, 20]; each landmark is seen from 2..n of them
};

/// Random nonlinear problems (see the file comment). The layouts point to a
/// static PoseManifold. Throws std::invalid_argument on sizes out of range.
marginalization::EquivalenceProblems RandomNonlinearProblems(const NonlinearProblemSizes& sizes,
                                                             unsigned seed);

struct VerifyOptions {
  unsigned seed = 1;        ///< first seed; trial k uses seed + k
  int num_landmarks = 6;    ///< landmarks / features per problem (see NonlinearProblemSizes)
  int num_poses = 4;        ///< MSCKF poses per problem
  int trials = 20;          ///< random problems per kind, >= 1
  double tolerance = 1e-8;  ///< largest relative deviation that counts as equal
};

/// One line of the report: a theorem (or control) on one kind of problem.
struct VerifyRow {
  std::string theorem;  ///< "4.3.1" ... "R4.3.2"
  std::string description;
  std::string kind;      ///< "linear" or "nonlinear"
  bool control = false;  ///< a negative control: must exceed the tolerance
  /// Largest over the trials; for a control the smallest (every trial's
  /// control must differ). NaN if any trial gave NaN.
  marginalization::Deviation deviation;
  bool passed = false;  ///< within tolerance, or (control) beyond it
};

struct VerifyReport {
  VerifyOptions options;
  std::vector<VerifyRow> rows;
  bool passed = false;  ///< every row passed
};

/// Runs every check on options.trials problems of each kind. Throws
/// std::invalid_argument on options out of range.
VerifyReport RunVerification(const VerifyOptions& options);

/// The report as a fixed-width text table with a verdict line.
std::string FormatVerifyReport(const VerifyReport& report);

}  // namespace vio::tools
