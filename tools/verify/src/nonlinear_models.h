#pragma once
// The nonlinear models of `vio verify` (private to vio_verify), each
// linearized at a given point for both forms of the equivalence theorems:
//
//   state x = (pose [p_w_b, q_w_b] on vio::PoseManifold (7 / 6), body velocity v_b (3))
//   h(pose, f)  rectified stereo (u_L, u_R, v) of landmark f (vio::StereoFactor)
//   ℓ(pose, z)  its inverse, stereo triangulation (the EKF's inverse measurement map)
//   g(x)        constant body velocity: (p + R v dt, q ⊗ dq, v)
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "vio/estimator/pose_manifold.h"
#include "vio/estimator/types.h"
#include "vio/marginalization/equivalence.h"

namespace vio::tools::verify_models {

inline constexpr double kSigmaPx = 1.0;   ///< stereo measurement noise [px]
inline constexpr double kDt = 0.1;        ///< motion model time step [s]
inline constexpr int kStateAmbient = 10;  ///< [p_w_b, q_w_b, v_b]
inline constexpr int kStateTangent = 9;   ///< [dp, dtheta, dv]

/// The pose manifold every layout of the nonlinear problems points to.
const PoseManifold& Manifold();

/// The rectified stereo rig: camera z along body x, x along -y_b, y along -z_b.
RectifiedStereo Camera();

/// [p_w_b, q_w_b (x y z w)] of a pose.
Eigen::Matrix<double, 7, 1> PoseVector(const Eigen::Vector3d& p_w_b, const Eigen::Quaterniond& q_w_b);
/// q_w_b of a pose (or state) vector.
Eigen::Quaterniond Rotation(const Eigen::VectorXd& pose);

/// h(pose, f) [px]; throws std::runtime_error when f is behind the camera.
Eigen::Vector3d Project(const Eigen::VectorXd& pose, const Eigen::Vector3d& p_w_l);

/// z - h(pose, f) and the tangent Jacobians of h at (pose, f).
struct StereoLinearization {
  Eigen::Vector3d innovation;
  Eigen::Matrix<double, 3, 6> H_pose;  ///< ∂h/∂[dp, dtheta]
  Eigen::Matrix3d H_f;                 ///< ∂h/∂f
};
StereoLinearization LinearizeStereo(const Eigen::Vector3d& z, const Eigen::VectorXd& pose,
                                    const Eigen::Vector3d& p_w_l);

/// ℓ(pose, z) and its Jacobians.
struct InverseMeasurement {
  Eigen::Vector3d p_w_l;
  Eigen::Matrix<double, 3, 6> L_pose;  ///< ∂ℓ/∂[dp, dtheta]
  Eigen::Matrix3d L_z;                 ///< ∂ℓ/∂z
};
/// Throws std::runtime_error when the disparity is below 1 px.
InverseMeasurement Triangulate(const Eigen::VectorXd& pose, const Eigen::Vector3d& z);

/// The motion model's known body rotation per step.
struct Motion {
  Eigen::Quaterniond dq = Eigen::Quaterniond::Identity();
};
/// g(x), ambient (10).
Eigen::VectorXd Propagate(const Motion& motion, const Eigen::VectorXd& x);
/// G = ∂(g(x ⊞ δ) ⊟ g(x))/∂δ (9 x 9), analytic.
Eigen::MatrixXd MotionJacobian(const Motion& motion, const Eigen::VectorXd& x);
/// r = x_{t+1} ⊟ g(x_t) and its tangent Jacobians, by autodiff.
marginalization::DynamicsResidual MotionResidualAt(const Motion& motion, const Eigen::VectorXd& x_t,
                                                   const Eigen::VectorXd& x_t1);

}  // namespace vio::tools::verify_models
