#pragma once
// `vio verify`: the design paper's equivalence theorems (4.3.1-4.3.5) and
// the filter forms of its Algorithms 3 (EKF) and 4 (MSCKF), checked THROUGH
// THE ESTIMATOR: each filter step is built as a cost in a vio::Window with the
// window's own factors and operations, the window takes the policy's
// Gauss-Newton step (Window::TakeSteps, step gn) after Window::Marginalize
// where the theorem marginalizes, and its mean and covariance (the inverse
// of Window::Information at the linearization point: after Marginalize, the
// information of the marginalization prior) are compared with the
// independent Kalman-form code (vio/marginalization/kalman_reference.h) on
// the same linearized factors. Two kinds of random problems:
//
//   linear     linear factors r0 + J (x ⊟ x*) (Window::AddLinearFactor) with
//              random J and r0 in place of the stereo and IMU factors;
//   nonlinear  window states (SE3 pose, speed, biases) and landmarks, stereo
//              observations (vio::StereoFactor through Window::AddObservation)
//              and preintegrated IMU intervals (vio::ImuFactor through
//              Window::AddImuFactor), linearized away from their zero so that
//              every mean carries an innovation.
//
// Negative controls break the optimization side (a factor with a wrong
// Jacobian, one Levenberg-Marquardt step, the wrong state marginalized) or
// the filter side (no null-space projection, a wrong H) and must be detected.
#include <string>
#include <vector>

#include "vio/marginalization/gaussian_state.h"

namespace vio::tools {

struct VerifyOptions {
  unsigned seed = 1;        ///< first seed; trial k uses seed + k
  int num_landmarks = 6;    ///< landmarks (EKF) / features (MSCKF) per problem, in [1, 50]
  int num_poses = 4;        ///< MSCKF poses per problem, in [2, 20]
  int trials = 20;          ///< random problems per kind, >= 1
  double tolerance = 1e-8;  ///< largest relative deviation that counts as equal
};

/// One line of the report: a theorem (or control) on one kind of problem.
struct VerifyRow {
  std::string theorem;  ///< "4.3.1" ... "4.3.5", "Alg. 3", "Alg. 4"
  std::string description;
  std::string kind;      ///< "linear" or "nonlinear"
  bool control = false;  ///< a negative control: must exceed the tolerance
  /// Largest over the trials; for a control the smallest (every trial's
  /// control must differ). NaN if any trial gave NaN.
  marginalization::Deviation deviation;
  /// Smallest over the trials of |e0|, the whitened residual of the step's
  /// factors at the linearization point (the innovation that moves the mean).
  double innovation = 0.0;
  std::string path;  ///< the code path of the optimization side ("window")
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
