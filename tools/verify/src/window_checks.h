#pragma once
// The equivalence checks through vio::Window (private to vio_verify): each
// case of window_cases.h is built in a Window, which takes the policy's step
// (Window::TakeSteps with step gn, after Window::Marginalize for the
// marginalization theorems); its mean is read from the window and its
// covariance is the inverse of Window::Information at the linearization point
// (after Marginalize: the information of the marginalization prior and the
// untouched priors). The reference is the Kalman-form code of
// vio/marginalization/kalman_reference.h on the same linearized factors.
#include <string>
#include <vector>

#include "vio/marginalization/gaussian_state.h"
#include "window_cases.h"

namespace vio::tools {

/// One check on one case.
struct WindowCheck {
  std::string theorem;      ///< "4.3.1" ... "4.3.5", "Alg. 3", "Alg. 4"
  std::string description;
  marginalization::Deviation deviation;  ///< of the window's result from the Kalman form
  double innovation = 0.0;  ///< |e0| of the case's factors at the linearization point (whitened)
  std::string path;         ///< the code path of the optimization side: "window"
};

/// Every theorem and algorithm on the cases.
std::vector<WindowCheck> CheckThroughWindow(const window_cases::CaseSet& cases);

/// Negative controls on the cases: the optimization side broken (one factor
/// with a 1e-4 relative Jacobian error, one Levenberg-Marquardt step instead
/// of Gauss-Newton, the wrong state marginalized) or the filter side broken
/// (no null-space projection, H off by 1e-5). Each must deviate.
std::vector<WindowCheck> ControlsThroughWindow(const window_cases::CaseSet& cases);

}  // namespace vio::tools
