#include "vio/estimator/frozen_observations.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Eigenvalues>
#include <ceres/sized_cost_function.h>
#include <glog/logging.h>

#include "quadratic_landmark_factor.h"
#include "vio/estimator/window.h"

namespace vio {
namespace {

class QuadraticFactor final : public ceres::SizedCostFunction<4, 3> {
 public:
  QuadraticFactor(const Eigen::Vector3d& reference, const Eigen::Matrix3d& sqrt_information,
                  const Eigen::Vector3d& offset, double floor)
      : reference_(reference), sqrt_information_(sqrt_information), offset_(offset), floor_(floor) {}

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    const Eigen::Map<const Eigen::Vector3d> p(parameters[0]);
    Eigen::Map<Eigen::Vector3d> r(residuals);
    r = sqrt_information_ * (p - reference_) + offset_;
    residuals[3] = floor_;
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, 4, 3, Eigen::RowMajor>> j(jacobians[0]);
      j.topRows<3>() = sqrt_information_;
      j.row(3).setZero();
    }
    return true;
  }

 private:
  Eigen::Vector3d reference_;
  Eigen::Matrix3d sqrt_information_;
  Eigen::Vector3d offset_;
  double floor_;
};

}  // namespace

void AddToSummary(const Eigen::Vector3d& p, double f, const Eigen::Vector3d& g, const Eigen::Matrix3d& h,
                  LandmarkSummary& summary) {
  if (summary.observations == 0) summary.reference = p;
  const Eigen::Vector3d d = p - summary.reference;
  // f + g^T (x - d) + 1/2 (x - d)^T h (x - d), x = p' - reference.
  summary.information += h;
  summary.linear += g - h * d;
  summary.constant += f - g.dot(d) + 0.5 * d.dot(h * d);
  ++summary.observations;
}

void RemoveFromSummary(const SummarizedObservation& o, FrozenObservations& frozen) {
  const auto it = frozen.landmarks.find(o.landmark);
  CHECK(it != frozen.landmarks.end()) << "an observation taken out of a summary it is not in";
  LandmarkSummary& summary = it->second;
  const Eigen::Vector3d d = o.p - summary.reference;
  summary.information -= o.h;
  summary.linear -= o.g - o.h * d;
  summary.constant -= o.f - o.g.dot(d) + 0.5 * d.dot(o.h * d);
  if (--summary.observations == 0) frozen.landmarks.erase(it);
}

std::unique_ptr<ceres::CostFunction> QuadraticLandmarkFactor(const LandmarkSummary& summary) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(summary.information);
  const Eigen::Vector3d lambda = eigen.eigenvalues();
  Eigen::Matrix3d sqrt_information = Eigen::Matrix3d::Zero();
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  const double smallest = 1e-12 * std::max(lambda.maxCoeff(), 0.0);
  for (int k = 0; k < 3; ++k) {
    if (lambda(k) <= smallest || lambda(k) <= 0) continue;
    const Eigen::Vector3d v = eigen.eigenvectors().col(k);
    sqrt_information.row(k) = std::sqrt(lambda(k)) * v.transpose();
    offset(k) = v.dot(summary.linear) / std::sqrt(lambda(k));
  }
  const double floor = std::sqrt(std::max(0.0, 2 * summary.constant - offset.squaredNorm()));
  return std::make_unique<QuadraticFactor>(summary.reference, sqrt_information, offset, floor);
}

// Ceres' own evaluation of each residual with its loss (EvaluateResidualBlock): the
// corrected residual r and Jacobian J give the gradient J^T r and the Hessian J^T J
// that Levenberg-Marquardt would take of it, and the cost.
void Window::SummarizeObservationsOf(StateId state, FrozenObservations& frozen,
                                     std::vector<SummarizedObservation>* taken) const {
  for (auto it = observations_.lower_bound({state, LandmarkId(std::numeric_limits<std::int64_t>::min())});
       it != observations_.end() && it->first.first == state; ++it) {
    const Landmark& landmark = landmarks_.at(it->first.second);
    CHECK(!problem_->IsParameterBlockConstant(landmark.p_w)) << "summarized observation of a constant landmark";
    const ceres::ResidualBlockId residual = it->second.residual;
    std::vector<double*> blocks;
    problem_->GetParameterBlocksForResidualBlock(residual, &blocks);
    const int rows = problem_->GetCostFunctionForResidualBlock(residual)->num_residuals();
    Eigen::VectorXd r(rows);
    Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> jacobian(rows, 3);
    std::vector<double*> jacobians(blocks.size(), nullptr);
    const auto at = std::find(blocks.begin(), blocks.end(), landmark.p_w);
    CHECK(at != blocks.end()) << "an observation without its landmark block";
    jacobians[static_cast<size_t>(at - blocks.begin())] = jacobian.data();
    double cost = 0;
    if (!problem_->EvaluateResidualBlock(residual, true, &cost, r.data(), jacobians.data()) || !r.allFinite() ||
        !jacobian.allFinite()) {
      ++frozen.skipped;
      continue;
    }
    const SummarizedObservation part{landmark.id, landmark.position(), cost, jacobian.transpose() * r,
                                     jacobian.transpose() * jacobian};
    AddToSummary(part.p, part.f, part.g, part.h, frozen.landmarks[landmark.id]);
    if (taken != nullptr) taken->push_back(part);
  }
}

// The residuals on the state in id order (priors, the IMU factors into and out of it, its
// observations), each evaluated with its loss as Ceres' Levenberg-Marquardt takes it.
Eigen::Matrix<double, 15, 1> Window::StateStep(StateId id) {
  State& s = state(id);
  std::vector<ceres::ResidualBlockId> residuals;
  for (const Prior& prior : priors_) {
    const bool on_state = std::any_of(prior.keys.begin(), prior.keys.end(), [id](const BlockKey& k) { return k.IsOf(id); });
    if (on_state) residuals.push_back(prior.residual);
  }
  if (const auto into = imu_edges_.find(id); into != imu_edges_.end()) residuals.push_back(into->second.residual);
  if (const auto out = imu_edges_.upper_bound(id); out != imu_edges_.end() && out->second.from == id) {
    residuals.push_back(out->second.residual);
  }
  for (auto it = observations_.lower_bound({id, LandmarkId(std::numeric_limits<std::int64_t>::min())});
       it != observations_.end() && it->first.first == id; ++it) {
    residuals.push_back(it->second.residual);
  }
  const bool was_constant = IsStateConstant(id);
  SetStateConstant(id, false);  // Ceres evaluates no Jacobian of a constant block
  Eigen::Matrix<double, 15, 15> h = Eigen::Matrix<double, 15, 15>::Zero();
  Eigen::Matrix<double, 15, 1> g = Eigen::Matrix<double, 15, 1>::Zero();
  for (const ceres::ResidualBlockId residual : residuals) {
    std::vector<double*> blocks;
    problem_->GetParameterBlocksForResidualBlock(residual, &blocks);
    const int rows = problem_->GetCostFunctionForResidualBlock(residual)->num_residuals();
    Eigen::VectorXd r(rows);
    Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor> j_pose = Eigen::MatrixXd::Zero(rows, 6);
    Eigen::Matrix<double, Eigen::Dynamic, 9, Eigen::RowMajor> j_speed_bias = Eigen::MatrixXd::Zero(rows, 9);
    std::vector<double*> jacobians(blocks.size(), nullptr);
    for (size_t k = 0; k < blocks.size(); ++k) {
      if (blocks[k] == s.pose) jacobians[k] = j_pose.data();
      if (blocks[k] == s.speed_bias) jacobians[k] = j_speed_bias.data();
    }
    double cost = 0;
    if (!problem_->EvaluateResidualBlock(residual, true, &cost, r.data(), jacobians.data()) || !r.allFinite()) continue;
    Eigen::Matrix<double, Eigen::Dynamic, 15> j(rows, 15);
    j << j_pose, j_speed_bias;
    if (!j.allFinite()) continue;
    h.noalias() += j.transpose() * j;
    g.noalias() += j.transpose() * r;
  }
  SetStateConstant(id, was_constant);
  const Eigen::Matrix<double, 15, 1> step = h.ldlt().solve(-g);
  return step.allFinite() ? step : Eigen::Matrix<double, 15, 1>::Zero();
}

}  // namespace vio
