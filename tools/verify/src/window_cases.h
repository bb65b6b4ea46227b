#pragma once
// The cases `vio verify` runs through vio::Window (private to vio_verify):
// one filter step each, as a cost the window builds with its own operations
// and as the linearized models the Kalman-form reference code
// (vio/marginalization/kalman_reference.h) takes.
//
// Variables are window states ([pose (7 / 6 tangent), speed_bias (9)]) and
// landmarks (3), stacked states first, then landmarks, in the order listed.
// A case is a Gaussian prior N(μ, Σ) over some of them (the filter's state,
// added to the window as one linear factor Σ^-1/2 (x ⊟ μ)), the values of all
// of them at the linearization point (the prior's part is μ) and factors:
//   nonlinear  StereoFactor (Window::AddObservation, 1 px, no robust loss) and
//              ImuFactor (Window::AddImuFactor, a preintegrated 0.1 s interval);
//   linear     the same structure with linear factors r0 + J (x ⊟ x*)
//              (Window::AddLinearFactor) of random J and r0: linear-Gaussian
//              in the variables' local coordinates.
// Both sides read the factors linearized at the same point: whitened
// e(x* ⊞ δ) ≈ e0 + J δ, a measurement with innovation e0, H = -J and noise I.
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <ceres/cost_function.h>

#include <Eigen/Core>

#include "vio/estimator/estimator_options.h"
#include "vio/estimator/imu_preintegration.h"
#include "vio/estimator/types.h"
#include "vio/estimator/window.h"
#include "vio/marginalization/gaussian_state.h"

namespace vio::tools::window_cases {

/// An ordered list of window variables.
struct Variables {
  std::vector<StateId> states;
  std::vector<LandmarkId> landmarks;

  marginalization::StateLayout Layout() const;
  /// Tangent column of a state's pose (its speed_bias follows at + 6) / of a
  /// landmark; -1 when not listed.
  int Column(StateId id) const;
  int Column(LandmarkId id) const;
  int TangentSize() const { return 15 * static_cast<int>(states.size()) + 3 * static_cast<int>(landmarks.size()); }
};

/// The values of every variable of a case (ambient).
struct Values {
  std::map<StateId, State> states;
  std::map<LandmarkId, Eigen::Vector3d> landmarks;

  /// Stacked ambient values of `variables`.
  Eigen::VectorXd Stack(const Variables& variables) const;
  /// Sets the values of `variables` from a stacked ambient vector.
  void Unstack(const Variables& variables, const Eigen::VectorXd& stacked);
  /// The values of `variables` in a window.
  static Eigen::VectorXd FromWindow(const Window& window, const Variables& variables);
};

/// One factor of a case.
struct Factor {
  enum class Kind { kStereo, kImu, kLinear };
  Kind kind = Kind::kStereo;
  Variables variables;  ///< stereo: (state, landmark); imu: (from, to); linear: any
  Eigen::Vector3d z_px = Eigen::Vector3d::Zero();      ///< stereo
  std::shared_ptr<const ImuPreintegration> preintegration;  ///< imu
  Eigen::MatrixXd jacobian;  ///< linear: over `variables`' tangent
  Eigen::VectorXd residual;  ///< linear: r0 at the linearization point
};

/// A factor linearized at a point: whitened e(x* ⊞ δ) ≈ e0 + J δ, J over
/// the columns of a Variables list.
struct Linearization {
  Eigen::VectorXd e0;
  Eigen::MatrixXd J;
};

/// Everything a check needs.
struct Case {
  Variables prior_variables;         ///< the filter state x̃_t, in the filter's order
  marginalization::Gaussian prior;   ///< N(μ, Σ) over prior_variables
  Values point;                      ///< every variable at the linearization point
  std::vector<Factor> factors;
};

/// The window model of the cases: 1 px stereo noise, no robust loss.
ModelOptions Model();
/// The rectified stereo rig of the cases.
RectifiedStereo Stereo();
/// Gravity vector in world [m/s^2].
Eigen::Vector3d Gravity();

/// A new cost function of the factor (the filter side's copy) and its
/// parameter blocks at `values`.
std::unique_ptr<ceres::CostFunction> CostFunction(const Factor& factor, const Values& values);
/// The factors linearized at `values`, stacked, J over `columns`.
Linearization Linearize(const std::vector<Factor>& factors, const Values& values, const Variables& columns);

/// The window of a case: every variable at its point value, the prior as one
/// linear factor, the factors through the window's own Add* calls. With
/// `wrap_first_factor`, the first factor is handed to the wrapper.
std::unique_ptr<Window> BuildWindow(const Case& c, const Window::FactorWrapper& wrap_first_factor = {});

/// Random cases (kind "linear" or "nonlinear"), one per check. Sizes: p
/// landmarks (EKF) / features (MSCKF), n poses (MSCKF).
struct CaseSet {
  Case ekf_augmentation;   ///< prior (x, f_1..p), new features f_new observed once from x
  int num_new_features = 0;
  Case ekf_update;         ///< prior (x, f_1..p), each f seen from x
  Case ekf_propagation;    ///< prior (x_t, f), IMU factor to x_{t+1}
  Case msckf_update;       ///< prior (x_IMU, x_1..x_n), features seen from 2..n of the x_i
  Case msckf_propagation;  ///< prior (x_IMU, x_1..x_n), IMU factor to x_{t+1}
  Case ekf_step;           ///< Algorithm 3: prior (x_{t-1}, f), IMU factor to x_t at the prediction, f seen from x_t
  Case msckf_step;         ///< Algorithm 4: prior (x_IMU, x_1..x_n), IMU factor to x_new at the prediction, features seen from the x_i and x_new
};
CaseSet RandomCases(const std::string& kind, int num_landmarks, int num_poses, unsigned seed);

}  // namespace vio::tools::window_cases
