#include "vio/estimator/inertial_alignment.h"

#include <Eigen/Dense>
#include <glog/logging.h>

#include "vio/estimator/so3.h"

namespace vio {
namespace {

// The gravity unknowns: free (3 columns) or on the sphere |g| = G around
// `direction` (g = G direction + B w, 2 columns).
struct GravityParameters {
  bool free = true;
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();
  double norm = 0;
  Eigen::Matrix<double, 3, 2> B = Eigen::Matrix<double, 3, 2>::Zero();
  int columns() const { return free ? 3 : 2; }
};

Eigen::Matrix<double, 3, 2> TangentBasis(const Eigen::Vector3d& direction, double norm) {
  Eigen::Vector3d a = direction.cross(Eigen::Vector3d::UnitX());
  if (a.norm() < 0.1) a = direction.cross(Eigen::Vector3d::UnitY());
  a.normalize();
  Eigen::Matrix<double, 3, 2> B;
  B << a, direction.cross(a).normalized();
  return norm * B;
}

// One 3-row equation group: coefficients on v_from, v_to, g, b_a and its
// right-hand side, with one standard deviation for its rows.
struct RowGroup {
  int from = 0;
  Eigen::Matrix3d c_from, c_to, c_g, c_ba;
  Eigen::Vector3d rhs;
  double sigma = 1;
};

std::vector<RowGroup> RowGroups(const std::vector<Eigen::Isometry3d>& T_0_k,
                                const std::vector<ImuPreintegration>& preintegrations, double position_sigma_m) {
  std::vector<RowGroup> groups;
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  for (size_t k = 1; k < T_0_k.size(); ++k) {
    const ImuPreintegration& pre = preintegrations[k - 1];
    const double dt = pre.delta_time_s();
    const Eigen::Matrix3d R = T_0_k[k - 1].linear();
    const ImuPreintegration::Deltas& d = pre.deltas();
    const double var_v = pre.covariance().block<3, 3>(3, 3).trace() / 3.0;
    const double var_p = pre.covariance().block<3, 3>(6, 6).trace() / 3.0;
    RowGroup velocity{static_cast<int>(k - 1), -I, I, -dt * I, -R * pre.d_delta_v_d_ba(), R * d.delta_v,
                      std::sqrt(var_v + 1e-12)};
    const Eigen::Vector3d dp = T_0_k[k].translation() - T_0_k[k - 1].translation() - R * d.delta_p;
    RowGroup position{static_cast<int>(k - 1), dt * I, Eigen::Matrix3d::Zero(), 0.5 * dt * dt * I,
                      R * pre.d_delta_p_d_ba(), dp, std::sqrt(var_p + 2 * position_sigma_m * position_sigma_m)};
    groups.push_back(velocity);
    groups.push_back(position);
  }
  return groups;
}

// Whitened least squares over [v_0 .. v_{N-1}, g (3 or 2), b_a].
Eigen::VectorXd SolveRows(const std::vector<RowGroup>& groups, int num_frames, const GravityParameters& gravity,
                          double accel_bias_sigma) {
  const int g_col = 3 * num_frames, ba_col = g_col + gravity.columns();
  const int rows = 3 * static_cast<int>(groups.size()) + 3, cols = ba_col + 3;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(rows, cols);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(rows);
  for (size_t i = 0; i < groups.size(); ++i) {
    const RowGroup& r = groups[i];
    const int row = 3 * static_cast<int>(i);
    const double w = 1.0 / r.sigma;
    A.block<3, 3>(row, 3 * r.from) += w * r.c_from;
    A.block<3, 3>(row, 3 * (r.from + 1)) += w * r.c_to;
    A.block<3, 3>(row, ba_col) = w * r.c_ba;
    b.segment<3>(row) = w * r.rhs;
    if (gravity.free) {
      A.block<3, 3>(row, g_col) = w * r.c_g;
    } else {
      A.block<3, 2>(row, g_col) = w * r.c_g * gravity.B;
      b.segment<3>(row) -= w * r.c_g * (gravity.norm * gravity.direction);
    }
  }
  A.block<3, 3>(rows - 3, ba_col) = Eigen::Matrix3d::Identity() / accel_bias_sigma;
  return A.colPivHouseholderQr().solve(b);
}

}  // namespace

Eigen::Vector3d AlignGyroBias(const std::vector<Eigen::Isometry3d>& T_0_k,
                              const std::vector<ImuPreintegration>& preintegrations) {
  CHECK_EQ(T_0_k.size(), preintegrations.size() + 1);
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  for (size_t k = 1; k < T_0_k.size(); ++k) {
    const ImuPreintegration& pre = preintegrations[k - 1];
    const Eigen::Matrix3d R_vision = T_0_k[k - 1].linear().transpose() * T_0_k[k].linear();
    const Eigen::Vector3d r = so3::Log(Eigen::Matrix3d(pre.deltas().delta_q.toRotationMatrix().transpose() * R_vision));
    const Eigen::Matrix3d J = pre.d_delta_R_d_bg();
    H += J.transpose() * J;
    g += J.transpose() * r;
  }
  const Eigen::Vector3d bias = preintegrations.empty() ? Eigen::Vector3d::Zero()
                                                       : Eigen::Vector3d(preintegrations.front().linearization_bias().gyro);
  return bias + H.ldlt().solve(g);
}

VelocityGravity AlignVelocityGravity(const std::vector<Eigen::Isometry3d>& T_0_k,
                                     const std::vector<ImuPreintegration>& preintegrations, double gravity,
                                     double accel_bias_sigma, double position_sigma_m) {
  CHECK_EQ(T_0_k.size(), preintegrations.size() + 1);
  const int n = static_cast<int>(T_0_k.size());
  const std::vector<RowGroup> groups = RowGroups(T_0_k, preintegrations, position_sigma_m);
  GravityParameters g;
  Eigen::VectorXd x = SolveRows(groups, n, g, accel_bias_sigma);
  VelocityGravity out;
  const Eigen::Vector3d g_free = x.segment<3>(3 * n);
  out.free_gravity_norm = g_free.norm();
  g.free = false;
  g.norm = gravity;
  g.direction = g_free.norm() > 1e-9 ? Eigen::Vector3d(g_free.normalized()) : Eigen::Vector3d(0, 0, -1);
  for (int iteration = 0; iteration < 4; ++iteration) {
    g.B = TangentBasis(g.direction, gravity);
    x = SolveRows(groups, n, g, accel_bias_sigma);
    g.direction = (gravity * g.direction + g.B * x.segment<2>(3 * n)).normalized();
  }
  out.g_0 = gravity * g.direction;
  for (int k = 0; k < n; ++k) out.v_0.push_back(x.segment<3>(3 * k));
  out.accel_bias = x.segment<3>(3 * n + 2);
  return out;
}

}  // namespace vio
