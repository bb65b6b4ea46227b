#pragma once
// The motion model of `vio verify`'s nonlinear problems and its residual on
// the pose manifold (autodiff), used as the dynamics term of the paper's
// propagation costs c_EKF,t,5 / c_MSCKF,t,5.
//
// State x = (pose [p_w_b, q_w_b] (7), body velocity v_b (3)). Constant body
// velocity and a known body rotation increment dq = Exp(omega dt):
//   g(p, q, v) = (p + R(q) v dt,  q ⊗ dq,  v).
// Residual of x_{t+1} against g(x_t) (PoseManifold Minus + Euclidean):
//   r = [p_{t+1} - p_g,  Log(q_g^-1 ⊗ q_{t+1}),  v_{t+1} - v_t]     (9)
// with Log(q) = 2 atan2(|v|, w) v / |v| (w >= 0), 2 v / w for |v|² < 1e-20
// (first-order exact, which autodiff needs at r = 0). Parameter blocks:
// pose_t (7), v_t (3), pose_{t+1} (7), v_{t+1} (3).
#include <ceres/autodiff_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace vio::tools {

class VerifyMotionResidual {
 public:
  VerifyMotionResidual(const Eigen::Quaterniond& dq, double dt) : dq_(dq), dt_(dt) {}

  static ceres::CostFunction* Create(const Eigen::Quaterniond& dq, double dt) {
    return new ceres::AutoDiffCostFunction<VerifyMotionResidual, 9, 7, 3, 7, 3>(
        new VerifyMotionResidual(dq, dt));
  }

  template <typename T>
  bool operator()(const T* pose_t, const T* v_t, const T* pose_t1, const T* v_t1, T* residual) const {
    using Vector3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Vector3> p(pose_t), v(v_t), p1(pose_t1), v1(v_t1);
    const Eigen::Map<const Eigen::Quaternion<T>> q(pose_t + 3), q1(pose_t1 + 3);
    const Eigen::Quaternion<T> q_g = q * dq_.cast<T>();
    const Vector3 p_g = p + q * (v * T(dt_));
    Eigen::Map<Eigen::Matrix<T, 9, 1>> r(residual);
    r.template head<3>() = p1 - p_g;
    r.template segment<3>(3) = Log(q_g.conjugate() * q1);
    r.template tail<3>() = v1 - v;
    return true;
  }

 private:
  template <typename T>
  static Eigen::Matrix<T, 3, 1> Log(const Eigen::Quaternion<T>& q) {
    const T sign = q.w() < T(0) ? T(-1) : T(1);
    const Eigen::Matrix<T, 3, 1> v = sign * q.vec();
    const T w = sign * q.w();
    const T squared_norm = v.squaredNorm();
    if (squared_norm < T(1e-20)) return (T(2) / w) * v;
    using std::atan2;
    using std::sqrt;
    const T norm = sqrt(squared_norm);
    return (T(2) * atan2(norm, w) / norm) * v;
  }

  Eigen::Quaterniond dq_;
  double dt_;
};

}  // namespace vio::tools
