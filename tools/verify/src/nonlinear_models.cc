// The nonlinear models of `vio verify` (see nonlinear_models.h).
#include "nonlinear_models.h"

#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include "motion_residual.h"
#include "vio/estimator/so3.h"
#include "vio/estimator/stereo_factor.h"
#include "vio/estimator/stereo_geometry.h"

namespace vio::tools::verify_models {
namespace {

constexpr double kMinDisparityPx = 1.0;

std::runtime_error Error(const std::string& what) {
  return std::runtime_error(std::string(__FILE__) + ": " + what);
}

}  // namespace

const PoseManifold& Manifold() {
  static const PoseManifold manifold;
  return manifold;
}

Eigen::Matrix<double, 7, 1> PoseVector(const Eigen::Vector3d& p_w_b, const Eigen::Quaterniond& q_w_b) {
  Eigen::Matrix<double, 7, 1> pose;
  pose << p_w_b, q_w_b.normalized().coeffs();
  return pose;
}

Eigen::Quaterniond Rotation(const Eigen::VectorXd& pose) {
  return Eigen::Quaterniond(pose[6], pose[3], pose[4], pose[5]).normalized();
}

RectifiedStereo Camera() {
  RectifiedStereo stereo;
  Eigen::Matrix3d R_b_c;
  R_b_c << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  stereo.T_b_cl.linear() = R_b_c;
  stereo.T_b_cl.translation() = Eigen::Vector3d(0.05, -0.02, 0.01);
  return stereo;
}

// ---------------------------------------------------------------------------
// Measurement model h (StereoFactor) and its inverse ℓ (stereo triangulation).

// From the factor: its residual is e = (z - h) / σ, so z - h = σ e and
// ∂h/∂. = -σ ∂e/∂. (tangent: ambient Jacobian times PlusJacobian).
StereoLinearization LinearizeStereo(const Eigen::Vector3d& z, const Eigen::VectorXd& pose,
                                    const Eigen::Vector3d& p_w_l) {
  const std::unique_ptr<ceres::CostFunction> factor(StereoFactor::Create(z, Camera(), kSigmaPx));
  const double* parameters[] = {pose.data(), p_w_l.data()};
  Eigen::Vector3d e;
  Eigen::Matrix<double, 3, 7, Eigen::RowMajor> J_pose_ambient;
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> J_f;
  double* jacobians[] = {J_pose_ambient.data(), J_f.data()};
  if (!factor->Evaluate(parameters, e.data(), jacobians)) {
    throw Error("a landmark is behind the camera");
  }
  Eigen::Matrix<double, 7, 6, Eigen::RowMajor> plus_jacobian;
  Manifold().PlusJacobian(pose.data(), plus_jacobian.data());
  return {kSigmaPx * e, -kSigmaPx * J_pose_ambient * plus_jacobian, -kSigmaPx * J_f};
}

Eigen::Vector3d Project(const Eigen::VectorXd& pose, const Eigen::Vector3d& p_w_l) {
  Eigen::Vector3d z;
  if (!StereoFactor::Project(Camera(), pose.head<3>(), Rotation(pose), p_w_l, &z)) {
    throw Error("a landmark is behind the camera");
  }
  return z;
}

// ℓ(pose, z) = p_w_b + R_w_b p_b, p_b = R_b_c p_c(z) + p_b_c, p_c triangulated:
//   ∂ℓ/∂[dp, dθ] = [I, -R_w_b [p_b]x]   (R Exp(dθ) p_b ≈ R p_b - R [p_b]x dθ),
//   ∂ℓ/∂z = R_w_b R_b_c ∂p_c/∂z,  p_c = b / d (u_L - cx, v - cy, f), d = u_L - u_R.
InverseMeasurement Triangulate(const Eigen::VectorXd& pose, const Eigen::Vector3d& z) {
  const RectifiedStereo stereo = Camera();
  const std::optional<Eigen::Vector3d> p_c = TriangulateRectified(z, stereo, kMinDisparityPx);
  if (!p_c) throw Error("disparity too small to triangulate");
  const double d = z[0] - z[1], b = stereo.baseline;
  const double x_u = z[0] - stereo.cx, y_v = z[2] - stereo.cy;
  Eigen::Matrix3d dpc_dz;                                       // rows x, y, z of p_c; columns u_L, u_R, v
  dpc_dz << b / d - x_u * b / (d * d), x_u * b / (d * d), 0.0,  //
      -y_v * b / (d * d), y_v * b / (d * d), b / d,             //
      -stereo.f * b / (d * d), stereo.f * b / (d * d), 0.0;
  const Eigen::Matrix3d R_w_b = Rotation(pose).toRotationMatrix();
  const Eigen::Vector3d p_b = stereo.T_b_cl * *p_c;
  InverseMeasurement result;
  result.p_w_l = pose.head<3>() + R_w_b * p_b;
  result.L_pose << Eigen::Matrix3d::Identity(), -R_w_b * so3::Hat(p_b);
  result.L_z = R_w_b * stereo.T_b_cl.linear() * dpc_dz;
  return result;
}

// ---------------------------------------------------------------------------
// Motion model g (see verify_motion_residual.h).

Eigen::VectorXd Propagate(const Motion& motion, const Eigen::VectorXd& x) {
  const Eigen::Quaterniond q = Rotation(x);
  Eigen::VectorXd g(kStateAmbient);
  g << x.head<3>() + q * x.tail<3>() * kDt, (q * motion.dq).normalized().coeffs(), x.tail<3>();
  return g;
}

// G = ∂(g(x ⊞ δ) ⊟ g(x))/∂δ = [[I, -R [v]x dt, R dt], [O, dR^T, O], [O, O, I]]:
// p + R Exp(dθ) (v + dv) dt ≈ p_g + dp - R [v]x dθ dt + R dv dt and
// q Exp(dθ) dq = q dq Exp(dR^T dθ).
Eigen::MatrixXd MotionJacobian(const Motion& motion, const Eigen::VectorXd& x) {
  const Eigen::Matrix3d R = Rotation(x).toRotationMatrix();
  Eigen::MatrixXd G = Eigen::MatrixXd::Identity(kStateTangent, kStateTangent);
  G.block<3, 3>(0, 3) = -R * so3::Hat(x.tail<3>()) * kDt;
  G.block<3, 3>(0, 6) = R * kDt;
  G.block<3, 3>(3, 3) = motion.dq.toRotationMatrix().transpose();
  return G;
}

// Tangent Jacobians: the autodiff ambient Jacobians times PlusJacobian.
marginalization::DynamicsResidual MotionResidualAt(const Motion& motion, const Eigen::VectorXd& x_t,
                                                   const Eigen::VectorXd& x_t1) {
  const std::unique_ptr<ceres::CostFunction> residual(VerifyMotionResidual::Create(motion.dq, kDt));
  const double* parameters[] = {x_t.data(), x_t.data() + 7, x_t1.data(), x_t1.data() + 7};
  using Ambient7 = Eigen::Matrix<double, 9, 7, Eigen::RowMajor>;
  using Ambient3 = Eigen::Matrix<double, 9, 3, Eigen::RowMajor>;
  Ambient7 J_pose_t, J_pose_t1;
  Ambient3 J_v_t, J_v_t1;
  double* jacobians[] = {J_pose_t.data(), J_v_t.data(), J_pose_t1.data(), J_v_t1.data()};
  marginalization::DynamicsResidual result{Eigen::VectorXd(kStateTangent),
                                           Eigen::MatrixXd(kStateTangent, kStateTangent),
                                           Eigen::MatrixXd(kStateTangent, kStateTangent)};
  if (!residual->Evaluate(parameters, result.r0.data(), jacobians)) {
    throw Error("motion residual evaluation failed");
  }
  Eigen::Matrix<double, 7, 6, Eigen::RowMajor> plus_t, plus_t1;
  Manifold().PlusJacobian(x_t.data(), plus_t.data());
  Manifold().PlusJacobian(x_t1.data(), plus_t1.data());
  result.J_from << J_pose_t * plus_t, J_v_t;
  result.J_to << J_pose_t1 * plus_t1, J_v_t1;
  return result;
}

}  // namespace vio::tools::verify_models
