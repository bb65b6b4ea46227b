// Covariance out of the window's information. On a linear-Gaussian problem
// (constant-velocity robot, static landmarks seen relative to it, old states
// and landmarks marginalized into a prior, the others eliminated) the
// newest state's marginal covariance equals the Kalman filter's (EKF-SLAM
// reference of the paper, kalman_reference.h) to 1e-9. On a nonlinear
// visual-inertial window it equals the block of the inverse of the whole
// J^T J (every block, Ceres' columns, dense).
#include <algorithm>
#include <map>
#include <memory>
#include <vector>

#include <ceres/crs_matrix.h>
#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include "synthetic_window.h"
#include "vio/estimator/window.h"
#include "vio/estimator/window_covariance.h"
#include "vio/marginalization/kalman_reference.h"
#include "vio/marginalization/marginalizer.h"

namespace vio {
namespace {

using marginalization::Gaussian;

constexpr int kRobot = 4;     // [p (2), v (2)]
constexpr int kLandmark = 2;  // p_l (2)
constexpr double kDt = 0.5;
constexpr double kSigmaZ = 0.1;
constexpr double kSigmaW = 0.05;

/// r = sum_i A_i x_i - b, all Euclidean.
class LinearFactor final : public ceres::CostFunction {
 public:
  LinearFactor(std::vector<Eigen::MatrixXd> A, Eigen::VectorXd b) : A_(std::move(A)), b_(std::move(b)) {
    set_num_residuals(static_cast<int>(b_.size()));
    for (const Eigen::MatrixXd& a : A_) mutable_parameter_block_sizes()->push_back(static_cast<int>(a.cols()));
  }
  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    Eigen::Map<Eigen::VectorXd> r(residuals, num_residuals());
    r = -b_;
    for (size_t i = 0; i < A_.size(); ++i) {
      r += A_[i] * Eigen::Map<const Eigen::VectorXd>(x[i], A_[i].cols());
      if (jacobians != nullptr && jacobians[i] != nullptr) {
        Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
            jacobians[i], A_[i].rows(), A_[i].cols()) = A_[i];
      }
    }
    return true;
  }

 private:
  std::vector<Eigen::MatrixXd> A_;
  Eigen::VectorXd b_;
};

Eigen::MatrixXd F() {
  Eigen::MatrixXd f = Eigen::MatrixXd::Identity(kRobot, kRobot);
  f.topRightCorner(2, 2) = kDt * Eigen::Matrix2d::Identity();
  return f;
}
Eigen::MatrixXd Qw() { return kSigmaW * kSigmaW * Eigen::MatrixXd::Identity(kRobot, kRobot); }
/// z = p_l - p + noise.
Eigen::MatrixXd C() {
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(kLandmark, kRobot);
  c.leftCols(2) = Eigen::Matrix2d::Identity();
  return c;
}
Eigen::MatrixXd P0() {
  Eigen::MatrixXd p0 = Eigen::MatrixXd::Identity(kRobot, kRobot) * 0.04;
  p0(0, 1) = p0(1, 0) = 0.01;
  return p0;
}
/// Landmarks seen at step k: k, k + 1, k + 2 (each for three steps).
std::vector<int> Seen(int k) { return {k, k + 1, k + 2}; }

/// The linear-Gaussian window: x_0..x_n, landmarks, factors whitened.
struct LinearWindow {
  std::vector<std::unique_ptr<double[]>> storage;
  ceres::Problem problem;
  std::vector<double*> states;
  std::map<int, double*> landmarks;
  double* NewBlock(int size, double value) {
    storage.push_back(std::make_unique<double[]>(static_cast<size_t>(size)));
    double* block = storage.back().get();
    for (int i = 0; i < size; ++i) block[i] = value + 0.1 * i;
    problem.AddParameterBlock(block, size);
    return block;
  }
};

void BuildLinearWindow(int steps, LinearWindow* w) {
  const Eigen::MatrixXd W0 = P0().llt().matrixL().solve(Eigen::MatrixXd::Identity(kRobot, kRobot));
  const Eigen::MatrixXd Ww = Eigen::MatrixXd::Identity(kRobot, kRobot) / kSigmaW;
  const Eigen::MatrixXd Wz = Eigen::MatrixXd::Identity(kLandmark, kLandmark) / kSigmaZ;
  for (int k = 0; k <= steps; ++k) {
    double* x = w->NewBlock(kRobot, 0.3 * k);
    if (k == 0) {
      w->problem.AddResidualBlock(new LinearFactor({W0}, W0 * Eigen::VectorXd::Constant(kRobot, 0.2)), nullptr, x);
    } else {
      double* previous = w->states.back();
      w->problem.AddResidualBlock(new LinearFactor({-Ww * F(), Ww}, Eigen::VectorXd::Zero(kRobot)), nullptr,
                                  previous, x);
    }
    w->states.push_back(x);
    for (int j : Seen(k)) {
      if (!w->landmarks.count(j)) w->landmarks[j] = w->NewBlock(kLandmark, 1.0 + j);
      w->problem.AddResidualBlock(new LinearFactor({-Wz * C(), Wz}, Wz * Eigen::Vector2d(0.5 * j, 1.0)), nullptr,
                                  x, w->landmarks[j]);
    }
  }
}

/// The Kalman filter over the same steps: propagate, augment the new
/// landmarks from their first measurement, update on the others.
Gaussian KalmanFilter(int steps) {
  Gaussian g{Eigen::VectorXd::Zero(kRobot), P0()};
  std::vector<int> order;  // landmark of each feature slot
  for (int k = 0; k <= steps; ++k) {
    if (k > 0) g = marginalization::EkfPropagate(g, {F() * g.mean.head(kRobot), F(), Qw()});
    const Eigen::MatrixXd Sv = kSigmaZ * kSigmaZ * Eigen::MatrixXd::Identity(kLandmark, kLandmark);
    for (int j : Seen(k)) {
      const auto slot = std::find(order.begin(), order.end(), j);
      if (slot == order.end()) {
        g = marginalization::EkfAugmentFeatures(g, kRobot, Eigen::Vector2d::Zero(), C(),
                                                Eigen::MatrixXd::Identity(kLandmark, kLandmark), Sv);
        order.push_back(j);
        continue;
      }
      marginalization::StateLayout layout;
      layout.AddEuclidean(static_cast<int>(g.mean.size()));
      marginalization::LinearizedMeasurements m;
      m.innovation = Eigen::Vector2d::Zero();
      m.H_x = Eigen::MatrixXd::Zero(kLandmark, g.mean.size());
      m.H_x.leftCols(kRobot) = -C();
      m.H_x.block(0, kRobot + kLandmark * (slot - order.begin()), kLandmark, kLandmark).setIdentity();
      m.Sigma_v = Sv;
      g = marginalization::EkfUpdate(g, layout, m);
    }
  }
  return g;
}

GaussNewtonLayout LayoutOf(ceres::Problem& problem, const std::vector<double*>& dense,
                           const std::vector<double*>& eliminated) {
  GaussNewtonLayout layout;
  layout.dense = dense;
  layout.eliminated = eliminated;
  problem.GetResidualBlocks(&layout.residuals);
  return layout;
}

TEST(WindowCovariance, LinearGaussianWindowEqualsTheKalmanFilter) {
  constexpr int kSteps = 8;
  constexpr int kMarginalized = 4;  // x_0..x_3 and the landmarks only they saw
  LinearWindow w;
  BuildLinearWindow(kSteps, &w);
  std::vector<double*> to_marginalize;
  for (int k = 0; k < kMarginalized; ++k) to_marginalize.push_back(w.states[static_cast<size_t>(k)]);
  for (int j = 0; j < kMarginalized; ++j) to_marginalize.push_back(w.landmarks[j]);
  const ceres::ResidualBlockId prior = marginalization::MarginalizeBlocks(&w.problem, to_marginalize);
  ASSERT_NE(prior, nullptr);
  std::vector<double*> in_prior;
  w.problem.GetParameterBlocksForResidualBlock(prior, &in_prior);

  std::vector<double*> dense, eliminated;
  for (int k = kMarginalized; k <= kSteps; ++k) dense.push_back(w.states[static_cast<size_t>(k)]);
  for (int j = kMarginalized; j < kSteps + 3; ++j) {
    double* l = w.landmarks[j];
    const bool tied = std::find(in_prior.begin(), in_prior.end(), l) != in_prior.end();
    (tied ? dense : eliminated).push_back(l);
  }
  ASSERT_FALSE(eliminated.empty());
  ASSERT_GT(dense.size(), static_cast<size_t>(kSteps + 1 - kMarginalized));  // a landmark tied by the prior

  const std::optional<Eigen::MatrixXd> covariance =
      MarginalCovariance(&w.problem, LayoutOf(w.problem, dense, eliminated), {w.states.back()});
  ASSERT_TRUE(covariance.has_value());
  const Eigen::MatrixXd expected = KalmanFilter(kSteps).covariance.topLeftCorner(kRobot, kRobot);
  EXPECT_LE((*covariance - expected).norm(), 1e-9 * expected.norm()) << *covariance << "\n\n" << expected;
}

TEST(WindowCovariance, SingularInformationGivesNothing) {
  ceres::Problem problem;
  double x[2] = {0, 0};
  problem.AddResidualBlock(new LinearFactor({Eigen::RowVector2d(1, 0)}, Eigen::VectorXd::Zero(1)), nullptr, x);
  EXPECT_FALSE(MarginalCovariance(&problem, LayoutOf(problem, {x}, {}), {x}).has_value());
}

ModelOptions Model() {
  ModelOptions model;
  model.huber_px = 0;
  return model;
}

const test::SyntheticFlight& Flight() {
  static const test::SyntheticFlight flight(6.0, 7);
  return flight;
}

/// The inverse of the whole J^T J (every block; Ceres' column order).
Eigen::MatrixXd DenseCovariance(ceres::Problem& problem, const std::vector<double*>& blocks) {
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks = blocks;
  ceres::CRSMatrix crs;
  EXPECT_TRUE(problem.Evaluate(evaluate, nullptr, nullptr, nullptr, &crs));
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int i = 0; i < crs.num_rows; ++i) {
    for (int a = crs.rows[i]; a < crs.rows[i + 1]; ++a) J(i, crs.cols[a]) = crs.values[a];
  }
  return (J.transpose() * J).inverse();
}

TEST(WindowCovariance, NewestStateEqualsTheDenseInverseOnAVisualInertialWindow) {
  Window window(Model(), Flight().stereo());
  Flight().Build(window, Model(), 60, 8);
  window.Marginalize({StateId(0), StateId(1)}, {});
  const std::optional<StateCovariance> covariance = NewestStateCovariance(window);
  ASSERT_TRUE(covariance.has_value());
  EXPECT_EQ(covariance->id, StateId(7));

  // Newest state first, so its block is the top-left 15x15.
  const State& newest = window.states().rbegin()->second;
  std::vector<double*> blocks{const_cast<double*>(newest.pose), const_cast<double*>(newest.speed_bias)};
  for (const auto& [id, s] : window.states()) {
    if (id == newest.id) continue;
    blocks.push_back(const_cast<double*>(s.pose));
    blocks.push_back(const_cast<double*>(s.speed_bias));
  }
  for (const auto& [id, l] : window.landmarks()) blocks.push_back(const_cast<double*>(l.p_w));
  const Eigen::MatrixXd expected =
      DenseCovariance(window.problem(), blocks).topLeftCorner(kStateTangentSize, kStateTangentSize);
  EXPECT_LE((covariance->covariance - expected).norm(), 1e-8 * expected.norm());
  // A state 6 s into a flight with a 1 mm first-pose prior: positions known to cm.
  const double position_variance = covariance->covariance.topLeftCorner<3, 3>().trace();
  EXPECT_LT(position_variance, 1e-2);
}

}  // namespace
}  // namespace vio
