#pragma once
// Test helpers of the estimator math tests (header only): an analytic
// synthetic motion with its IMU readings, random states, and a checker of
// cost-function Jacobians against central differences on the tangent space.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <ceres/cost_function.h>
#include <ceres/manifold.h>
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "vio/estimator/so3.h"
#include "vio/marginalization/tangent_cost_function.h"
#include "vio/estimator/types.h"

namespace vio::test {

/// The true state of the synthetic motion at one instant.
struct MotionState {
  Eigen::Vector3d p_w_b = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_w_b = Eigen::Quaterniond::Identity();
  Eigen::Vector3d v_w_b = Eigen::Vector3d::Zero();
  Eigen::Vector3d a_w_b = Eigen::Vector3d::Zero();    ///< world acceleration [m/s^2]
  Eigen::Vector3d omega_b = Eigen::Vector3d::Zero();  ///< body angular rate [rad/s]
};

/// Analytic motion:
///   p(t) = p0 + v0 t + a0 t^2 / 2 + A .* sin(fp t)       (componentwise)
///   R(t) = R0 Exp(w0 t) Exp(s(t) u),  s(t) = c sin(fw t),  |u| = 1
/// so w_b(t) = Exp(s u)^T w0 + s'(t) u. With A = 0 and c = 0 it is a constant
/// body rate with a constant world acceleration.
struct SyntheticMotion {
  Eigen::Vector3d p0 = Eigen::Vector3d(1.0, -2.0, 0.5);
  Eigen::Quaterniond q0 = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
  Eigen::Vector3d v0 = Eigen::Vector3d(0.8, 0.3, -0.2);    ///< [m/s]
  Eigen::Vector3d a0 = Eigen::Vector3d(0.4, -0.3, 0.2);    ///< [m/s^2]
  Eigen::Vector3d w0 = Eigen::Vector3d(0.3, -0.2, 0.5);    ///< [rad/s]
  double wobble_rad = 0.0;                                 ///< c
  double wobble_rad_s = 0.0;                               ///< fw
  Eigen::Vector3d wobble_axis = Eigen::Vector3d(0.0, 1.0, 0.0);
  Eigen::Vector3d position_amplitude_m = Eigen::Vector3d::Zero();  ///< A
  double position_rad_s = 0.0;                                     ///< fp

  /// A non-trivial smooth motion (time-varying rate and acceleration).
  static SyntheticMotion Wavy() {
    SyntheticMotion motion;
    motion.wobble_rad = 0.4;
    motion.wobble_rad_s = 2.0;
    motion.position_amplitude_m = Eigen::Vector3d(0.3, 0.2, 0.1);
    motion.position_rad_s = 1.5;
    return motion;
  }

  MotionState At(double t) const {
    const Eigen::Vector3d sin_p = (position_rad_s * t * Eigen::Vector3d::Ones()).array().sin();
    const Eigen::Vector3d cos_p = (position_rad_s * t * Eigen::Vector3d::Ones()).array().cos();
    const double s = wobble_rad * std::sin(wobble_rad_s * t);
    const double s_dot = wobble_rad * wobble_rad_s * std::cos(wobble_rad_s * t);
    const Eigen::Quaterniond q_wobble = so3::ExpQuaternion(s * wobble_axis);
    MotionState state;
    state.p_w_b = p0 + v0 * t + 0.5 * a0 * t * t + position_amplitude_m.cwiseProduct(sin_p);
    state.v_w_b = v0 + a0 * t + position_rad_s * position_amplitude_m.cwiseProduct(cos_p);
    state.a_w_b = a0 - position_rad_s * position_rad_s * position_amplitude_m.cwiseProduct(sin_p);
    state.q_w_b = (q0 * so3::ExpQuaternion(w0 * t) * q_wobble).normalized();
    state.omega_b = q_wobble.conjugate() * w0 + s_dot * wobble_axis;
    return state;
  }

  /// Noise-free IMU reading at t_ns with the given biases and gravity.
  ImuSample Imu(Timestamp t_ns, const Eigen::Vector3d& b_g, const Eigen::Vector3d& b_a,
                const Eigen::Vector3d& g_w = Eigen::Vector3d(0, 0, -9.81)) const {
    const MotionState state = At(NanosToSeconds(t_ns));
    ImuSample sample;
    sample.t_ns = t_ns;
    sample.gyro_rad_s = state.omega_b + b_g;
    sample.accel_m_s2 = state.q_w_b.conjugate() * (state.a_w_b - g_w) + b_a;
    return sample;
  }

  /// Readings every period_ns from first_ns up to and including >= last_ns.
  std::vector<ImuSample> ImuSamples(Timestamp first_ns, Timestamp last_ns, Timestamp period_ns,
                                    const Eigen::Vector3d& b_g, const Eigen::Vector3d& b_a) const {
    std::vector<ImuSample> samples;
    for (Timestamp t = first_ns; t < last_ns + period_ns; t += period_ns) {
      samples.push_back(Imu(t, b_g, b_a));
    }
    return samples;
  }
};

/// Pose block [p, q(x y z w)] of a position and rotation.
inline std::vector<double> PoseBlock(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  const Eigen::Quaterniond u = q.normalized();
  return {p.x(), p.y(), p.z(), u.x(), u.y(), u.z(), u.w()};
}

/// Speed-bias block [v, b_g, b_a].
inline std::vector<double> SpeedBiasBlock(const Eigen::Vector3d& v, const Eigen::Vector3d& b_g,
                                          const Eigen::Vector3d& b_a) {
  return {v.x(), v.y(), v.z(), b_g.x(), b_g.y(), b_g.z(), b_a.x(), b_a.y(), b_a.z()};
}

/// Uniform random vector in [-scale, scale]^n from a seeded engine.
template <int N>
Eigen::Matrix<double, N, 1> RandomVector(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> uniform(-scale, scale);
  Eigen::Matrix<double, N, 1> v;
  for (int i = 0; i < N; ++i) v[i] = uniform(rng);
  return v;
}

using MatrixXdRowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// Residuals of `cost` at `parameters`; false when Evaluate fails.
inline bool EvaluateResiduals(const ceres::CostFunction& cost,
                              const std::vector<std::vector<double>>& parameters,
                              Eigen::VectorXd* residuals) {
  std::vector<const double*> blocks;
  for (const auto& block : parameters) blocks.push_back(block.data());
  residuals->resize(cost.num_residuals());
  return cost.Evaluate(blocks.data(), residuals->data(), nullptr);
}

/// x boxplus delta for one block (Euclidean when manifold is null).
inline std::vector<double> BlockPlus(const ceres::Manifold* manifold, const std::vector<double>& x,
                                     const Eigen::VectorXd& delta) {
  std::vector<double> result(x.size());
  if (manifold == nullptr) {
    for (size_t i = 0; i < x.size(); ++i) result[i] = x[i] + delta[static_cast<int>(i)];
  } else {
    manifold->Plus(x.data(), delta.data(), result.data());
  }
  return result;
}

/// Tangent-space Jacobians of every block: analytic (ambient Jacobian times
/// the manifold's PlusJacobian) and numeric (central differences through
/// Plus with step h). Fails the test if Evaluate fails.
inline void TangentJacobians(const ceres::CostFunction& cost,
                             const std::vector<std::vector<double>>& parameters,
                             const std::vector<const ceres::Manifold*>& manifolds, double h,
                             std::vector<Eigen::MatrixXd>* analytic,
                             std::vector<Eigen::MatrixXd>* numeric) {
  const int num_residuals = cost.num_residuals();
  std::vector<const double*> blocks;
  std::vector<MatrixXdRowMajor> ambient;
  std::vector<double*> jacobian_pointers;
  for (size_t b = 0; b < parameters.size(); ++b) {
    blocks.push_back(parameters[b].data());
    ambient.emplace_back(num_residuals, static_cast<int>(parameters[b].size()));
  }
  for (auto& J : ambient) jacobian_pointers.push_back(J.data());
  Eigen::VectorXd residuals(num_residuals);
  ASSERT_TRUE(cost.Evaluate(blocks.data(), residuals.data(), jacobian_pointers.data()));

  for (size_t b = 0; b < parameters.size(); ++b) {
    const ceres::Manifold* manifold = manifolds[b];
    const int tangent_size = manifold ? manifold->TangentSize() : static_cast<int>(parameters[b].size());
    MatrixXdRowMajor plus_jacobian = MatrixXdRowMajor::Identity(parameters[b].size(), tangent_size);
    if (manifold != nullptr) manifold->PlusJacobian(parameters[b].data(), plus_jacobian.data());
    analytic->push_back(ambient[b] * plus_jacobian);

    Eigen::MatrixXd J(num_residuals, tangent_size);
    for (int k = 0; k < tangent_size; ++k) {
      const Eigen::VectorXd delta = h * Eigen::VectorXd::Unit(tangent_size, k);
      auto plus = parameters, minus = parameters;
      plus[b] = BlockPlus(manifold, parameters[b], delta);
      minus[b] = BlockPlus(manifold, parameters[b], -delta);
      Eigen::VectorXd r_plus, r_minus;
      ASSERT_TRUE(EvaluateResiduals(cost, plus, &r_plus));
      ASSERT_TRUE(EvaluateResiduals(cost, minus, &r_minus));
      J.col(k) = (r_plus - r_minus) / (2.0 * h);
    }
    numeric->push_back(J);
  }
}

/// Expects every block's analytic tangent Jacobian to match central
/// differences: |J_analytic - J_numeric| <= relative_tolerance * max(|J_numeric|, 1)
/// (Frobenius norms, per block).
inline void ExpectTangentJacobiansMatch(const ceres::CostFunction& cost,
                                        const std::vector<std::vector<double>>& parameters,
                                        const std::vector<const ceres::Manifold*>& manifolds,
                                        double relative_tolerance, double h = 1e-6) {
  std::vector<Eigen::MatrixXd> analytic, numeric;
  TangentJacobians(cost, parameters, manifolds, h, &analytic, &numeric);
  ASSERT_EQ(analytic.size(), parameters.size());
  for (size_t b = 0; b < parameters.size(); ++b) {
    const double error = (analytic[b] - numeric[b]).norm();
    EXPECT_LE(error, relative_tolerance * std::max(numeric[b].norm(), 1.0))
        << "block " << b << "\nanalytic:\n" << analytic[b] << "\nnumeric:\n" << numeric[b];
  }
}

/// A TangentCostFunction's tangent Jacobians equal its ambient ones times
/// each manifold's PlusJacobian (nullptr: Euclidean), and its residual is the
/// same, to `relative_tolerance`.
inline void ExpectTangentEvaluationMatchesAmbient(const ceres::CostFunction& cost,
                                                  const std::vector<std::vector<double>>& parameters,
                                                  const std::vector<const ceres::Manifold*>& manifolds,
                                                  double relative_tolerance = 1e-12) {
  const auto* on_tangents = dynamic_cast<const marginalization::TangentCostFunction*>(&cost);
  ASSERT_NE(on_tangents, nullptr);
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const int rows = cost.num_residuals();
  std::vector<const double*> values;
  std::vector<RowMajor> ambient, tangent;
  std::vector<double*> ambient_pointers, tangent_pointers;
  for (size_t b = 0; b < parameters.size(); ++b) {
    values.push_back(parameters[b].data());
    const int size = static_cast<int>(parameters[b].size());
    ambient.emplace_back(rows, size);
    tangent.emplace_back(rows, manifolds[b] != nullptr ? manifolds[b]->TangentSize() : size);
  }
  for (size_t b = 0; b < parameters.size(); ++b) {
    ambient_pointers.push_back(ambient[b].data());
    tangent_pointers.push_back(tangent[b].data());
  }
  Eigen::VectorXd r_ambient(rows), r_tangent(rows);
  ASSERT_TRUE(cost.Evaluate(values.data(), r_ambient.data(), ambient_pointers.data()));
  ASSERT_TRUE(on_tangents->EvaluateOnTangents(values.data(), r_tangent.data(), tangent_pointers.data()));
  EXPECT_EQ(r_tangent, r_ambient);
  for (size_t b = 0; b < parameters.size(); ++b) {
    RowMajor expected = ambient[b];
    if (manifolds[b] != nullptr) {
      RowMajor plus(manifolds[b]->AmbientSize(), manifolds[b]->TangentSize());
      ASSERT_TRUE(manifolds[b]->PlusJacobian(parameters[b].data(), plus.data()));
      expected = ambient[b] * plus;
    }
    EXPECT_LE((tangent[b] - expected).norm(), relative_tolerance * std::max(expected.norm(), 1.0)) << "block " << b;
  }
}

}  // namespace vio::test
