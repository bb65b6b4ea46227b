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
void Window::SummarizeObservationsOf(StateId state, FrozenObservations& frozen) const {
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
    AddToSummary(landmark.position(), cost, jacobian.transpose() * r, jacobian.transpose() * jacobian,
                 frozen.landmarks[landmark.id]);
  }
}

}  // namespace vio
