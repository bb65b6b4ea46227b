// The equivalence checks through vio::Window (see window_checks.h).
#include "window_checks.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <memory>
#include <utility>

#include "vio/estimator/estimator_options.h"
#include "vio/marginalization/kalman_reference.h"

namespace vio::tools {
namespace {

using marginalization::Gaussian;
using marginalization::LinearizedDynamics;
using marginalization::LinearizedMeasurements;
using window_cases::Case;
using window_cases::CaseSet;
using window_cases::Factor;
using window_cases::Linearization;
using window_cases::Variables;

constexpr double kWrongJacobian = 1e-4;  // relative error of the control's factor Jacobian
constexpr double kWrongH = 1e-5;         // relative error of the control filter's H

// ---------------------------------------------------------------------------
// The optimization side: the window.

/// What the window is asked to do before its Gauss-Newton step.
struct WindowOperation {
  std::vector<StateId> marginalize_states;
  std::vector<LandmarkId> marginalize_landmarks;
  std::string step = "gn";                   ///< gn | lm (a control)
  Window::FactorWrapper wrap_first_factor;  ///< a control: the first factor wrapped
};

/// Build, marginalize, read the information at the linearization point, take
/// one step, read the mean: N(mean, information^-1) over `kept`.
Gaussian ThroughWindow(const Case& c, const WindowOperation& operation, const Variables& kept) {
  const std::unique_ptr<Window> window = window_cases::BuildWindow(c, operation.wrap_first_factor);
  window->Marginalize(operation.marginalize_states, operation.marginalize_landmarks);
  const Eigen::MatrixXd information = window->Information(kept.states, kept.landmarks);
  SolverOptions options;
  options.step = operation.step;
  window->TakeSteps(1, options);
  const Eigen::MatrixXd identity = Eigen::MatrixXd::Identity(information.rows(), information.cols());
  return {window_cases::Values::FromWindow(*window, kept), information.ldlt().solve(identity)};
}

/// A factor whose Jacobians are off by kWrongJacobian (relative).
class WrongJacobian final : public ceres::CostFunction {
 public:
  explicit WrongJacobian(ceres::CostFunction* inner) : inner_(inner) {
    set_num_residuals(inner->num_residuals());
    *mutable_parameter_block_sizes() = inner->parameter_block_sizes();
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    if (!inner_->Evaluate(parameters, residuals, jacobians)) return false;
    if (jacobians == nullptr) return true;
    for (size_t i = 0; i < parameter_block_sizes().size(); ++i) {
      if (jacobians[i] == nullptr) continue;
      for (int k = 0; k < num_residuals() * parameter_block_sizes()[i]; ++k) jacobians[i][k] *= 1.0 + kWrongJacobian;
    }
    return true;
  }

 private:
  std::unique_ptr<ceres::CostFunction> inner_;
};

// ---------------------------------------------------------------------------
// The filter side: the Kalman forms on the linearized factors.

/// Measurements e(x* ⊞ δ) ≈ e0 + J δ (whitened): innovation e0, H = -J, noise I;
/// H_x over `states`, H_f over `features` (empty: none).
LinearizedMeasurements Measurements(const std::vector<Factor>& factors, const Case& c, const Variables& states,
                                    const Variables& features = {}) {
  Variables columns = states;
  columns.landmarks.insert(columns.landmarks.end(), features.landmarks.begin(), features.landmarks.end());
  const Linearization lin = window_cases::Linearize(factors, c.point, columns);
  const Eigen::Index m = lin.e0.size(), d = states.TangentSize();
  return {lin.e0, -lin.J.leftCols(d), -lin.J.rightCols(lin.J.cols() - d), Eigen::MatrixXd::Identity(m, m)};
}

/// The dynamics of an IMU (or linear) factor e(x_t, x_{t+1}) ≈ e0 + A δ_t + B δ_{t+1}
/// with noise I: x_{t+1} = x*_{t+1} ⊞ (-B^-1 (e0 + A δ_t) + B^-1 n), i.e.
/// g(μ) = x* ⊞ (-B^-1 e0), G = -B^-1 A, Σ_w = B^-1 B^-T (tangent at x*_{t+1}).
LinearizedDynamics Dynamics(const Factor& factor, const Case& c) {
  const Variables pair{factor.variables.states, {}};
  const Linearization lin = window_cases::Linearize({factor}, c.point, pair);
  const Eigen::PartialPivLU<Eigen::MatrixXd> B(lin.J.rightCols(15));
  const Variables to{{factor.variables.states.back()}, {}};
  const Eigen::MatrixXd B_inv = B.inverse();
  return {to.Layout().Plus(c.point.Stack(to), -B_inv * lin.e0), -B_inv * lin.J.leftCols(15),
          B_inv * B_inv.transpose()};
}

std::vector<Factor> OfKind(const Case& c, bool dynamics) {
  std::vector<Factor> factors;
  for (const Factor& f : c.factors) {
    const bool is_dynamics = f.variables.states.size() == 2;
    if (is_dynamics == dynamics) factors.push_back(f);
  }
  return factors;
}

double InnovationNorm(const Case& c) {
  Variables all;
  for (const auto& [id, s] : c.point.states) all.states.push_back(id);
  for (const auto& [id, l] : c.point.landmarks) all.landmarks.push_back(id);
  return window_cases::Linearize(c.factors, c.point, all).e0.norm();
}

Variables Features(const Case& c) {
  Variables features;
  for (const auto& [id, l] : c.point.landmarks) features.landmarks.push_back(id);
  return features;
}

/// The variables of a case: its prior's, then the new landmarks.
Variables AllOf(const Case& c) {
  Variables all = c.prior_variables;
  for (const auto& [id, l] : c.point.landmarks) {
    if (all.Column(id) < 0) all.landmarks.push_back(id);
  }
  return all;
}

WindowCheck Compare(std::string theorem, std::string description, const Case& c, const Gaussian& window,
                    const Gaussian& filter, const Variables& kept) {
  const marginalization::Deviation deviation =
      marginalization::Compare(window, filter, kept.Layout(), c.point.Stack(kept));
  return {std::move(theorem), std::move(description), deviation, InnovationNorm(c), "window"};
}

// ---------------------------------------------------------------------------
// The filter forms of each case.

/// Alg. 6 with the inverse measurement map linearized at the point: each new
/// feature's observation e ≈ e0 + J_x δ_x + J_f δ_f = 0 gives
/// f = f* ⊞ (-J_f^-1 e0), L_x = -J_f^-1 J_x, L_z = -J_f^-1 (noise I).
Gaussian EkfAugmentationFilter(const Case& c) {
  const int p_new = static_cast<int>(c.factors.size());
  Eigen::VectorXd means(3 * p_new);
  Eigen::MatrixXd L_x = Eigen::MatrixXd::Zero(3 * p_new, 15), L_z = Eigen::MatrixXd::Zero(3 * p_new, 3 * p_new);
  for (int k = 0; k < p_new; ++k) {
    const Factor& f = c.factors[static_cast<size_t>(k)];
    const Linearization lin = window_cases::Linearize({f}, c.point, f.variables);
    const Eigen::Matrix3d J_f_inv = lin.J.rightCols(3).inverse();
    means.segment<3>(3 * k) = c.point.landmarks.at(f.variables.landmarks.front()) - J_f_inv * lin.e0;
    L_x.middleRows<3>(3 * k) = -J_f_inv * lin.J.leftCols(15);
    L_z.block<3, 3>(3 * k, 3 * k) = -J_f_inv;
  }
  return marginalization::EkfAugmentFeatures(c.prior, 15, means, L_x, L_z,
                                             Eigen::MatrixXd::Identity(3 * p_new, 3 * p_new));
}

Gaussian EkfUpdateFilter(const Case& c, double h_error = 0.0) {
  LinearizedMeasurements meas = Measurements(c.factors, c, c.prior_variables);
  meas.H_x *= 1.0 + h_error;
  return marginalization::EkfUpdate(c.prior, c.prior_variables.Layout(), meas);
}

/// The variables after propagation: the new state first, the rest of the prior.
Variables Propagated(const Case& c, const Factor& dynamics) {
  Variables kept = c.prior_variables;
  kept.states.front() = dynamics.variables.states.back();
  return kept;
}

/// Alg. 10 then 12 with the whole state cloned (the window keeps whole states):
/// (x_IMU, x_1..x_n) -> (x_new, x_1..x_n, x_IMU).
Gaussian MsckfCloneAndPropagate(const Case& c, const Factor& dynamics) {
  Eigen::MatrixXd Psi = Eigen::MatrixXd::Zero(15, c.prior.covariance.rows());
  Psi.leftCols(15).setIdentity();
  const Gaussian cloned = marginalization::MsckfAugmentPose(c.prior, c.prior.mean.head(16), Psi);
  return marginalization::MsckfPropagate(cloned, Dynamics(dynamics, c));
}

Variables ClonedAndPropagated(const Case& c, const Factor& dynamics) {
  Variables kept = Propagated(c, dynamics);
  kept.states.push_back(c.prior_variables.states.front());
  return kept;
}

}  // namespace

std::vector<WindowCheck> CheckThroughWindow(const CaseSet& cases) {
  std::vector<WindowCheck> checks;
  {
    const Case& c = cases.ekf_augmentation;
    const Variables all = AllOf(c);
    checks.push_back(Compare("4.3.1", "EKF feature augmentation (Alg. 6) = 1 GN step on c_EKF,t,1", c,
                             ThroughWindow(c, {}, all), EkfAugmentationFilter(c), all));
  }
  {
    const Case& c = cases.ekf_update;
    checks.push_back(Compare("4.3.2", "EKF feature update (Alg. 7) = 1 GN step on c_EKF,t,3", c,
                             ThroughWindow(c, {}, c.prior_variables), EkfUpdateFilter(c), c.prior_variables));
  }
  {
    const Case& c = cases.ekf_propagation;
    const Factor& dynamics = c.factors.front();
    const Variables kept = Propagated(c, dynamics);
    checks.push_back(Compare("4.3.3", "EKF propagation (Alg. 8) = marginalizing x_t out of c_EKF,t,5", c,
                             ThroughWindow(c, {{c.prior_variables.states.front()}, {}, "gn", {}}, kept),
                             marginalization::EkfPropagate(c.prior, Dynamics(dynamics, c)), kept));
  }
  {
    const Case& c = cases.msckf_update;
    const Variables features = Features(c);
    checks.push_back(Compare(
        "4.3.4", "MSCKF feature update (Alg. 11) = marginalizing f out of c_MSCKF,t,3, 1 GN step", c,
        ThroughWindow(c, {{}, features.landmarks, "gn", {}}, c.prior_variables),
        marginalization::MsckfFeatureUpdate(c.prior, c.prior_variables.Layout(),
                                            Measurements(c.factors, c, c.prior_variables, features)),
        c.prior_variables));
  }
  {
    const Case& c = cases.msckf_propagation;
    const Factor& dynamics = c.factors.front();
    const Variables kept = Propagated(c, dynamics);
    checks.push_back(Compare("4.3.5", "MSCKF propagation (Alg. 12) = marginalizing x_IMU out of c_MSCKF,t,5", c,
                             ThroughWindow(c, {{c.prior_variables.states.front()}, {}, "gn", {}}, kept),
                             marginalization::MsckfPropagate(c.prior, Dynamics(dynamics, c)), kept));
  }
  {
    const Case& c = cases.ekf_step;
    const Factor dynamics = OfKind(c, true).front();
    const Variables kept = Propagated(c, dynamics);
    const Gaussian propagated = marginalization::EkfPropagate(c.prior, Dynamics(dynamics, c));
    const Gaussian filter = marginalization::EkfUpdate(propagated, kept.Layout(), Measurements(OfKind(c, false), c, kept));
    checks.push_back(Compare("Alg. 3", "EKF step (Alg. 8 + 7) = marginalize x_{t-1}, 1 GN step (policy ekf)", c,
                             ThroughWindow(c, {{c.prior_variables.states.front()}, {}, "gn", {}}, kept), filter,
                             kept));
  }
  {
    const Case& c = cases.msckf_step;
    const Factor dynamics = OfKind(c, true).front();
    const Variables kept = ClonedAndPropagated(c, dynamics);
    const Variables features = Features(c);
    const Gaussian filter = marginalization::MsckfFeatureUpdate(
        MsckfCloneAndPropagate(c, dynamics), kept.Layout(), Measurements(OfKind(c, false), c, kept, features));
    checks.push_back(Compare("Alg. 4",
                             "MSCKF step (Alg. 10 + 12 + 11) = new state, marginalize f, 1 GN step (policy msckf)", c,
                             ThroughWindow(c, {{}, features.landmarks, "gn", {}}, kept), filter, kept));
  }
  return checks;
}

std::vector<WindowCheck> ControlsThroughWindow(const CaseSet& cases) {
  std::vector<WindowCheck> controls;
  const Case& update = cases.ekf_update;
  const Gaussian update_filter = EkfUpdateFilter(update);
  const Window::FactorWrapper wrong = [](ceres::CostFunction* f) { return new WrongJacobian(f); };
  controls.push_back(Compare("4.3.2", "window: one factor's Jacobian off by 1e-4", update,
                             ThroughWindow(update, {{}, {}, "gn", wrong}, update.prior_variables), update_filter,
                             update.prior_variables));
  controls.push_back(Compare("4.3.2", "window: one Levenberg-Marquardt step instead of Gauss-Newton", update,
                             ThroughWindow(update, {{}, {}, "lm", {}}, update.prior_variables), update_filter,
                             update.prior_variables));
  {
    const Case& c = cases.ekf_propagation;
    const Factor& dynamics = c.factors.front();
    const Variables kept = Propagated(c, dynamics);
    Variables wrong_kept = kept;  // x_t kept, x_{t+1} marginalized
    wrong_kept.states.front() = c.prior_variables.states.front();
    const Gaussian window = ThroughWindow(c, {{dynamics.variables.states.back()}, {}, "gn", {}}, wrong_kept);
    controls.push_back(Compare("4.3.3", "window: x_{t+1} marginalized instead of x_t", c, window,
                               marginalization::EkfPropagate(c.prior, Dynamics(dynamics, c)), kept));
  }
  {
    const Case& c = cases.msckf_update;
    const Variables features = Features(c);
    LinearizedMeasurements known_features = Measurements(c.factors, c, c.prior_variables, features);
    known_features.H_f.resize(0, 0);
    controls.push_back(Compare("4.3.4", "filter: MSCKF update without null-space projection", c,
                               ThroughWindow(c, {{}, features.landmarks, "gn", {}}, c.prior_variables),
                               marginalization::EkfUpdate(c.prior, c.prior_variables.Layout(), known_features),
                               c.prior_variables));
  }
  controls.push_back(Compare("4.3.2", "filter: EKF update with H off by 1e-5", update,
                             ThroughWindow(update, {}, update.prior_variables), EkfUpdateFilter(update, kWrongH),
                             update.prior_variables));
  return controls;
}

}  // namespace vio::tools
