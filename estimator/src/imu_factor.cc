#include "vio/estimator/imu_factor.h"

#include <glog/logging.h>

#include "vio/estimator/pose_manifold.h"
#include "vio/estimator/so3.h"
#include "imu_state_index.h"

namespace vio {
namespace {

using imu_state_index::kBa;
using imu_state_index::kBg;
using imu_state_index::kP;
using imu_state_index::kR;
using imu_state_index::kV;

// Columns inside the speed-bias block [v, b_g, b_a] and the pose tangent
// [dp, dtheta].
constexpr int kSbVelocity = 0;
constexpr int kSbGyro = 3;
constexpr int kSbAccel = 6;
constexpr int kTangentPosition = 0;
constexpr int kTangentRotation = 3;

using Matrix15x6d = Eigen::Matrix<double, 15, 6>;
using Matrix15x9d = Eigen::Matrix<double, 15, 9>;
using Matrix15x9dRowMajor = Eigen::Matrix<double, 15, 9, Eigen::RowMajor>;

}  // namespace

/// The two states read from the parameter blocks.
struct ImuFactor::States {
  explicit States(double const* const* parameters)
      : p_i(parameters[0]), q_i(Eigen::Map<const Eigen::Quaterniond>(parameters[0] + 3).normalized()),
        v_i(parameters[1]), bg_i(parameters[1] + 3), ba_i(parameters[1] + 6),
        p_j(parameters[2]), q_j(Eigen::Map<const Eigen::Quaterniond>(parameters[2] + 3).normalized()),
        v_j(parameters[3]), bg_j(parameters[3] + 3), ba_j(parameters[3] + 6),
        R_i(q_i.toRotationMatrix()), R_j(q_j.toRotationMatrix()) {}

  Eigen::Map<const Eigen::Vector3d> p_i;
  Eigen::Quaterniond q_i;
  Eigen::Map<const Eigen::Vector3d> v_i, bg_i, ba_i, p_j;
  Eigen::Quaterniond q_j;
  Eigen::Map<const Eigen::Vector3d> v_j, bg_j, ba_j;
  Eigen::Matrix3d R_i, R_j;
};

/// The unwhitened residual and the intermediate terms its Jacobians reuse.
struct ImuFactor::Linearization {
  Vector15d residual;
  Eigen::Matrix3d E;            ///< dR_corrected^T R_i^T R_j
  Eigen::Vector3d phi_bias;     ///< dR/dbg (bg_i - bg_lin)
  Eigen::Vector3d velocity_i;   ///< R_i^T (v_j - v_i - g dt)
  Eigen::Vector3d position_i;   ///< R_i^T (p_j - p_i - v_i dt - g dt^2 / 2)
};

ImuFactor::ImuFactor(const ImuPreintegration& preintegration, const Eigen::Vector3d& g_w)
    : preintegration_(preintegration),
      g_w_(g_w),
      sqrt_information_(preintegration.SqrtInformation()) {}

ceres::CostFunction* ImuFactor::Create(const ImuPreintegration& preintegration,
                                       const Eigen::Vector3d& g_w) {
  return new ImuFactor(preintegration, g_w);
}

ImuFactor::Linearization ImuFactor::Linearize(const States& s) const {
  const ImuBias bias_i{s.bg_i, s.ba_i};
  const ImuPreintegration::Deltas d = preintegration_.CorrectedDeltas(bias_i);
  const double dt = preintegration_.delta_time_s();

  Linearization lin;
  lin.phi_bias = preintegration_.d_delta_R_d_bg() * (s.bg_i - preintegration_.linearization_bias().gyro);
  lin.E = d.delta_q.toRotationMatrix().transpose() * s.R_i.transpose() * s.R_j;
  lin.velocity_i = s.R_i.transpose() * (s.v_j - s.v_i - g_w_ * dt);
  lin.position_i = s.R_i.transpose() * (s.p_j - s.p_i - s.v_i * dt - 0.5 * g_w_ * dt * dt);
  lin.residual.segment<3>(kR) = so3::Log(lin.E);
  lin.residual.segment<3>(kV) = lin.velocity_i - d.delta_v;
  lin.residual.segment<3>(kP) = lin.position_i - d.delta_p;
  lin.residual.segment<3>(kBg) = s.bg_j - s.bg_i;
  lin.residual.segment<3>(kBa) = s.ba_j - s.ba_i;
  return lin;
}

ImuFactor::Vector15d ImuFactor::UnwhitenedResidual(double const* const* parameters) const {
  return Linearize(States(parameters)).residual;
}

bool ImuFactor::Evaluate(double const* const* parameters, double* residuals,
                         double** jacobians) const {
  return EvaluateImpl(parameters, residuals, jacobians, /*on_tangents=*/false);
}

bool ImuFactor::EvaluateOnTangents(double const* const* parameters, double* residuals,
                                   double** jacobians) const {
  return EvaluateImpl(parameters, residuals, jacobians, /*on_tangents=*/true);
}

bool ImuFactor::EvaluateImpl(double const* const* parameters, double* residuals, double** jacobians,
                             bool on_tangents) const {
  const States states(parameters);
  const Linearization lin = Linearize(states);
  Eigen::Map<Vector15d>{residuals} = sqrt_information_ * lin.residual;
  if (jacobians != nullptr) WriteJacobians(states, lin, jacobians, on_tangents);
  return true;
}

void ImuFactor::WriteJacobians(const States& s, const Linearization& lin, double** jacobians,
                               bool on_tangents) const {
  const auto write_pose = [on_tangents](const Matrix15x6d& J, const Eigen::Quaterniond& q, double* out) {
    if (on_tangents) {
      Eigen::Map<Eigen::Matrix<double, 15, 6, Eigen::RowMajor>>{out} = J;
    } else {
      PoseJacobianToAmbient<15>(J, q, out);
    }
  };
  const double dt = preintegration_.delta_time_s();
  const Eigen::Matrix3d Jr_inv = so3::RightJacobianInverse(lin.residual.segment<3>(kR));
  const Eigen::Matrix3d R_i_T = s.R_i.transpose();
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();

  if (jacobians[0] != nullptr) {  // pose_i
    Matrix15x6d J = Matrix15x6d::Zero();
    J.block<3, 3>(kR, kTangentRotation) = -Jr_inv * s.R_j.transpose() * s.R_i;
    J.block<3, 3>(kV, kTangentRotation) = so3::Hat(lin.velocity_i);
    J.block<3, 3>(kP, kTangentPosition) = -R_i_T;
    J.block<3, 3>(kP, kTangentRotation) = so3::Hat(lin.position_i);
    write_pose(sqrt_information_ * J, s.q_i, jacobians[0]);
  }
  if (jacobians[1] != nullptr) {  // speed_bias_i
    Matrix15x9d J = Matrix15x9d::Zero();
    J.block<3, 3>(kR, kSbGyro) = -Jr_inv * lin.E.transpose() * so3::RightJacobian(lin.phi_bias) *
                                 preintegration_.d_delta_R_d_bg();
    J.block<3, 3>(kV, kSbVelocity) = -R_i_T;
    J.block<3, 3>(kV, kSbGyro) = -preintegration_.d_delta_v_d_bg();
    J.block<3, 3>(kV, kSbAccel) = -preintegration_.d_delta_v_d_ba();
    J.block<3, 3>(kP, kSbVelocity) = -R_i_T * dt;
    J.block<3, 3>(kP, kSbGyro) = -preintegration_.d_delta_p_d_bg();
    J.block<3, 3>(kP, kSbAccel) = -preintegration_.d_delta_p_d_ba();
    J.block<3, 3>(kBg, kSbGyro) = -I;
    J.block<3, 3>(kBa, kSbAccel) = -I;
    Eigen::Map<Matrix15x9dRowMajor>{jacobians[1]} = sqrt_information_ * J;
  }
  if (jacobians[2] != nullptr) {  // pose_j
    Matrix15x6d J = Matrix15x6d::Zero();
    J.block<3, 3>(kR, kTangentRotation) = Jr_inv;
    J.block<3, 3>(kP, kTangentPosition) = R_i_T;
    write_pose(sqrt_information_ * J, s.q_j, jacobians[2]);
  }
  if (jacobians[3] != nullptr) {  // speed_bias_j
    Matrix15x9d J = Matrix15x9d::Zero();
    J.block<3, 3>(kV, kSbVelocity) = R_i_T;
    J.block<3, 3>(kBg, kSbGyro) = I;
    J.block<3, 3>(kBa, kSbAccel) = I;
    Eigen::Map<Matrix15x9dRowMajor>{jacobians[3]} = sqrt_information_ * J;
  }
}

}  // namespace vio
