// MarginalizationPrior: residual and Jacobians on Euclidean blocks and on
// Ceres' own manifolds, checked against central differences on the tangent
// space (the only derivative the solver ever uses).
#include "vio/marginalization/marginalization_prior.h"

#include <cmath>
#include <memory>
#include <random>
#include <stdexcept>
#include <vector>

#include <ceres/gradient_checker.h>
#include <ceres/manifold.h>
#include <ceres/product_manifold.h>
#include <gtest/gtest.h>

#include "vio/marginalization/local_coordinates_jacobian.h"

namespace vio::marginalization {
namespace {

using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using PoseManifold =
    ceres::ProductManifold<ceres::EuclideanManifold<3>, ceres::EigenQuaternionManifold>;

Eigen::Matrix3d Hat(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

// ceres::EigenQuaternionManifold (x ⊞ d = Exp(2 d) * x, x ⊟ x0 = Log(x * x0^-1) / 2,
// i.e. half rotation vectors, left perturbation) plus the closed-form
//   d Minus(x ⊞ d, x0) / d d = J_l^-1(phi),  phi = rotation vector of x * x0^-1,
//   J_l^-1(phi) = I - [phi]x / 2 + (1/theta^2 - (1 + cos theta) / (2 theta sin theta)) [phi]x^2.
class ExactQuaternionManifold final : public ceres::Manifold, public LocalCoordinatesJacobian {
 public:
  int AmbientSize() const override { return 4; }
  int TangentSize() const override { return 3; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override {
    return base_.Plus(x, delta, x_plus_delta);
  }
  bool PlusJacobian(const double* x, double* jacobian) const override {
    return base_.PlusJacobian(x, jacobian);
  }
  bool Minus(const double* y, const double* x, double* y_minus_x) const override {
    return base_.Minus(y, x, y_minus_x);
  }
  bool MinusJacobian(const double* x, double* jacobian) const override {
    return base_.MinusJacobian(x, jacobian);
  }
  bool MinusTangentJacobian(const double* x, const double* x0, double* jacobian) const override {
    ++calls;
    Eigen::Vector3d half_phi;
    base_.Minus(x, x0, half_phi.data());
    const Eigen::Vector3d phi = 2.0 * half_phi;
    const double theta = phi.norm();
    const double c =
        1.0 / (theta * theta) - (1.0 + std::cos(theta)) / (2.0 * theta * std::sin(theta));
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> d_minus_d_delta(jacobian);
    d_minus_d_delta = Eigen::Matrix3d::Identity() - 0.5 * Hat(phi) + c * Hat(phi) * Hat(phi);
    return true;
  }
  mutable int calls = 0;

 private:
  ceres::EigenQuaternionManifold base_;
};

// A prior over five blocks: plain Euclidean (nullptr), EuclideanManifold<2>,
// EigenQuaternionManifold, ProductManifold (position, quaternion) and the
// exact quaternion manifold above.
class MarginalizationPriorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    manifolds_ = {nullptr, &euclidean2_, &quaternion_, &pose_, &exact_quaternion_};
    x0_ = {{0.3, -1.2, 2.0},
           {5.0, -4.0},
           UnitQuaternion(0.1, 0.7, -0.2, 0.6),
           {1.0, 2.0, 3.0, -0.2, 0.4, 0.1, 0.9},
           UnitQuaternion(-0.4, 0.1, 0.3, 0.8)};
    Eigen::Map<Eigen::Vector4d>(&x0_[3][3]).normalize();
    std::vector<MarginalizationPrior::Block> blocks;
    for (size_t i = 0; i < x0_.size(); ++i) {
      blocks.push_back({manifolds_[i], x0_[i]});
    }
    std::mt19937 rng(7);
    std::normal_distribution<double> normal;
    Jp_ = Eigen::MatrixXd::NullaryExpr(20, 17, [&] { return normal(rng); });
    r0_ = Eigen::VectorXd::NullaryExpr(20, [&] { return normal(rng); });
    prior_ = MarginalizationPrior::Create(blocks, Jp_, r0_);
  }

  static std::vector<double> UnitQuaternion(double x, double y, double z, double w) {
    Eigen::Vector4d q(x, y, z, w);
    q.normalize();
    return {q[0], q[1], q[2], q[3]};
  }

  // x_i = x0_i ⊞ (scale * fixed pseudo-random tangent vector).
  std::vector<std::vector<double>> Perturbed(double scale) const {
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    std::vector<std::vector<double>> x = x0_;
    for (size_t i = 0; i < x.size(); ++i) {
      const int n = prior_->tangent_size(static_cast<int>(i));
      const Eigen::VectorXd delta =
          scale * Eigen::VectorXd::NullaryExpr(n, [&] { return uniform(rng); });
      PlusBlock(i, x0_[i].data(), delta.data(), x[i].data());
    }
    return x;
  }

  void PlusBlock(size_t i, const double* x, const double* delta, double* result) const {
    if (manifolds_[i] == nullptr) {
      for (size_t k = 0; k < x0_[i].size(); ++k)
        result[k] = x[k] + delta[k];
    } else {
      ASSERT_TRUE(manifolds_[i]->Plus(x, delta, result));
    }
  }

  Eigen::VectorXd Residual(const std::vector<std::vector<double>>& x) const {
    std::vector<const double*> parameters;
    for (const auto& block : x)
      parameters.push_back(block.data());
    Eigen::VectorXd r(prior_->num_residuals());
    EXPECT_TRUE(prior_->Evaluate(parameters.data(), r.data(), nullptr));
    return r;
  }

  // Analytic tangent Jacobian [J_amb,i * PlusJacobian(x_i)]_i stacked by columns.
  Eigen::MatrixXd AnalyticTangentJacobian(const std::vector<std::vector<double>>& x) const {
    std::vector<const double*> parameters;
    std::vector<RowMajorMatrix> ambient;
    std::vector<double*> jacobians;
    for (size_t i = 0; i < x.size(); ++i) {
      parameters.push_back(x[i].data());
      ambient.emplace_back(prior_->num_residuals(), static_cast<int>(x[i].size()));
    }
    for (auto& J : ambient)
      jacobians.push_back(J.data());
    Eigen::VectorXd r(prior_->num_residuals());
    EXPECT_TRUE(prior_->Evaluate(parameters.data(), r.data(), jacobians.data()));
    Eigen::MatrixXd tangent(prior_->num_residuals(), Jp_.cols());
    for (size_t i = 0; i < x.size(); ++i) {
      const int n = prior_->tangent_size(static_cast<int>(i));
      RowMajorMatrix plus_jacobian = RowMajorMatrix::Identity(static_cast<int>(x[i].size()), n);
      if (manifolds_[i] != nullptr) {
        EXPECT_TRUE(manifolds_[i]->PlusJacobian(x[i].data(), plus_jacobian.data()));
      }
      tangent.middleCols(prior_->tangent_offset(static_cast<int>(i)), n) =
          ambient[i] * plus_jacobian;
    }
    return tangent;
  }

  // Central differences of r(x_i ⊞ d) on every tangent coordinate.
  Eigen::MatrixXd NumericTangentJacobian(const std::vector<std::vector<double>>& x) const {
    const double h = 1e-6;
    Eigen::MatrixXd tangent(prior_->num_residuals(), Jp_.cols());
    for (size_t i = 0; i < x.size(); ++i) {
      const int n = prior_->tangent_size(static_cast<int>(i));
      for (int k = 0; k < n; ++k) {
        Eigen::VectorXd d = Eigen::VectorXd::Zero(n);
        std::vector<std::vector<double>> forward = x, backward = x;
        d(k) = h;
        PlusBlock(i, x[i].data(), d.data(), forward[i].data());
        d(k) = -h;
        PlusBlock(i, x[i].data(), d.data(), backward[i].data());
        tangent.col(prior_->tangent_offset(static_cast<int>(i)) + k) =
            (Residual(forward) - Residual(backward)) / (2.0 * h);
      }
    }
    return tangent;
  }

  ceres::EuclideanManifold<2> euclidean2_;
  ceres::EigenQuaternionManifold quaternion_;
  PoseManifold pose_;
  ExactQuaternionManifold exact_quaternion_;
  std::vector<const ceres::Manifold*> manifolds_;
  std::vector<std::vector<double>> x0_;
  Eigen::MatrixXd Jp_;
  Eigen::VectorXd r0_;
  std::unique_ptr<MarginalizationPrior> prior_;
};

TEST_F(MarginalizationPriorTest, SizesFollowTheBlocks) {
  EXPECT_EQ(prior_->num_residuals(), 20);
  ASSERT_EQ(prior_->parameter_block_sizes().size(), 5u);
  EXPECT_EQ(prior_->parameter_block_sizes()[3], 7);
  EXPECT_EQ(prior_->tangent_size(3), 6);
  EXPECT_EQ(prior_->tangent_offset(4), 3 + 2 + 3 + 6);
}

TEST_F(MarginalizationPriorTest, ResidualAtLinearizationPointIsR0) {
  EXPECT_LE((Residual(x0_) - r0_).norm(), 1e-14 * r0_.norm());
}

TEST_F(MarginalizationPriorTest, TangentJacobianAtLinearizationPointIsJp) {
  EXPECT_LE((AnalyticTangentJacobian(x0_) - Jp_).norm(), 1e-13 * Jp_.norm());
}

TEST_F(MarginalizationPriorTest, ResidualAwayFromX0IsR0PlusJpTimesLocalCoordinates) {
  const auto x = Perturbed(0.01);
  Eigen::VectorXd delta(Jp_.cols());
  delta << x[0][0] - x0_[0][0], x[0][1] - x0_[0][1], x[0][2] - x0_[0][2], x[1][0] - x0_[1][0],
      x[1][1] - x0_[1][1], Eigen::VectorXd::Zero(12);
  ASSERT_TRUE(quaternion_.Minus(x[2].data(), x0_[2].data(), delta.data() + 5));
  ASSERT_TRUE(pose_.Minus(x[3].data(), x0_[3].data(), delta.data() + 8));
  ASSERT_TRUE(exact_quaternion_.Minus(x[4].data(), x0_[4].data(), delta.data() + 14));
  EXPECT_LE((Residual(x) - (r0_ + Jp_ * delta)).norm(), 1e-13 * r0_.norm());
}

TEST_F(MarginalizationPriorTest, TangentJacobianAwayFromX0MatchesCentralDifferences) {
  const auto x = Perturbed(0.3);  // rotations of up to ~0.6 rad per axis
  const Eigen::MatrixXd analytic = AnalyticTangentJacobian(x);
  const Eigen::MatrixXd numeric = NumericTangentJacobian(x);
  EXPECT_LE((analytic - numeric).cwiseAbs().maxCoeff(), 1e-7 * Jp_.cwiseAbs().maxCoeff());
  EXPECT_GT(exact_quaternion_.calls, 0) << "the closed-form LocalCoordinatesJacobian was not used";
  // The first-order shortcut d(x ⊟ x0)/dd ~= I would be far off here, so the
  // comparison above really tests the exact derivative.
  EXPECT_GT((numeric - Jp_).cwiseAbs().maxCoeff(), 1e-2);
}

TEST_F(MarginalizationPriorTest, CeresGradientCheckerAcceptsTheAmbientJacobians) {
  const auto x = Perturbed(0.2);
  std::vector<const double*> parameters;
  for (const auto& block : x)
    parameters.push_back(block.data());
  ceres::NumericDiffOptions numeric_options;
  ceres::GradientChecker checker(prior_.get(), &manifolds_, numeric_options);
  ceres::GradientChecker::ProbeResults results;
  EXPECT_TRUE(checker.Probe(parameters.data(), 1e-6, &results)) << results.error_log;
}

TEST_F(MarginalizationPriorTest, TangentLinearizationIsTheJacobianProducts) {
  // What the Gauss-Newton solver and the marginalizer assemble from the stored
  // information equals J^T J, J^T r and 0.5 |r|^2 of the residual and tangent
  // Jacobian themselves, away from x0 where T_i != I.
  const auto x = Perturbed(0.3);
  std::vector<const double*> parameters;
  for (const auto& block : x) parameters.push_back(block.data());
  MarginalizationPrior::TangentLinearization at;
  ASSERT_TRUE(prior_->Linearize(parameters.data(), &at));
  const Eigen::MatrixXd J = AnalyticTangentJacobian(x);
  const Eigen::VectorXd r = Residual(x);
  const Eigen::MatrixXd JtJ = J.transpose() * J;
  const int blocks = static_cast<int>(x.size());
  int non_identity = 0;
  for (int i = 0; i < blocks; ++i) {
    non_identity += at.T[static_cast<size_t>(i)].size() > 0;
    for (int j = 0; j < blocks; ++j) {
      Eigen::MatrixXd block;
      prior_->TangentHessianBlock(at, i, j, &block);
      const auto expected = JtJ.block(prior_->tangent_offset(i), prior_->tangent_offset(j), prior_->tangent_size(i),
                                      prior_->tangent_size(j));
      EXPECT_LE((block - expected).norm(), 1e-12 * JtJ.norm()) << "block (" << i << ", " << j << ")";
    }
  }
  EXPECT_GT(non_identity, 0);
  EXPECT_LE((at.g - J.transpose() * r).norm(), 1e-12 * at.g.norm());
  EXPECT_NEAR(at.cost, 0.5 * r.squaredNorm(), 1e-12 * at.cost);
}

TEST(MarginalizationPriorLinearize, AtX0IsTheGeneralFormulaBitForBit) {
  // At x0 (delta exactly 0 on Euclidean blocks) the products with delta are skipped: g and the
  // cost are exactly what the general formula gives there, signs of zero included.
  Eigen::MatrixXd Jp(4, 5);
  Jp << 1.5, -0.25, 0, 2, 0.125, 0, 3, -1, 0.5, 0, 0, 0, 2.5, -0.75, 1, 0, 0, 0, 4, -2;
  Eigen::VectorXd r0(4);
  r0 << 0.5, -0.0, 1.25, -3;
  const std::vector<double> a{1, 2, 3};
  const std::vector<double> b{-1, 0.5};
  const auto prior = MarginalizationPrior::Create({{nullptr, a}, {nullptr, b}}, Jp, r0);
  const double* parameters[] = {a.data(), b.data()};
  MarginalizationPrior::TangentLinearization at;
  ASSERT_TRUE(prior->Linearize(parameters, &at));
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(5);
  const Eigen::VectorXd g = prior->information_vector() + prior->information() * zero;
  ASSERT_EQ(at.g.size(), g.size());
  for (Eigen::Index k = 0; k < g.size(); ++k) {
    EXPECT_EQ(at.g[k], g[k]) << k;
    EXPECT_EQ(std::signbit(at.g[k]), std::signbit(g[k])) << k;
  }
  EXPECT_EQ(at.cost, 0.5 * (r0 + Jp * zero).squaredNorm());
  for (const Eigen::MatrixXd& T : at.T) EXPECT_EQ(T.size(), 0);
}

TEST_F(MarginalizationPriorTest, LinearizationWithoutCostKeepsTheRest) {
  const auto x = Perturbed(0.3);
  std::vector<const double*> parameters;
  for (const auto& block : x) parameters.push_back(block.data());
  MarginalizationPrior::TangentLinearization with_cost;
  MarginalizationPrior::TangentLinearization without_cost;
  ASSERT_TRUE(prior_->Linearize(parameters.data(), &with_cost));
  ASSERT_TRUE(prior_->Linearize(parameters.data(), &without_cost, /*with_cost=*/false));
  EXPECT_GT(with_cost.cost, 0.0);
  EXPECT_EQ(without_cost.cost, 0.0);
  EXPECT_EQ(without_cost.g, with_cost.g);
  ASSERT_EQ(without_cost.T.size(), with_cost.T.size());
  for (size_t i = 0; i < with_cost.T.size(); ++i) EXPECT_EQ(without_cost.T[i], with_cost.T[i]) << i;
}

TEST_F(MarginalizationPriorTest, GivenInformationIsKeptAndChecked) {
  const Eigen::MatrixXd information = Jp_.transpose() * Jp_;
  std::vector<MarginalizationPrior::Block> blocks = prior_->blocks();
  const auto given = MarginalizationPrior::Create(blocks, Jp_, r0_, information);
  EXPECT_EQ(given->information(), information);
  EXPECT_LE((given->information() - prior_->information()).norm(), 1e-12 * information.norm());
  EXPECT_THROW(MarginalizationPrior::Create(blocks, Jp_, r0_, information.topRows(3)), std::invalid_argument);
  Eigen::MatrixXd not_finite = information;
  not_finite(1, 2) = std::nan("");
  EXPECT_THROW(MarginalizationPrior::Create(blocks, Jp_, r0_, not_finite), std::invalid_argument);
}

TEST(MarginalizationPriorCreate, RejectsInconsistentInput) {
  ceres::EigenQuaternionManifold quaternion;
  const Eigen::MatrixXd Jp = Eigen::MatrixXd::Identity(3, 3);
  const Eigen::VectorXd r0 = Eigen::VectorXd::Zero(3);
  EXPECT_THROW(MarginalizationPrior::Create({}, Jp, r0), std::invalid_argument);
  EXPECT_THROW(MarginalizationPrior::Create({{nullptr, {1.0, 2.0}}}, Jp, r0),
               std::invalid_argument);
  EXPECT_THROW(MarginalizationPrior::Create({{&quaternion, {0.0, 0.0, 1.0}}}, Jp, r0),
               std::invalid_argument);
  EXPECT_THROW(
      MarginalizationPrior::Create({{nullptr, {1.0, 2.0, 3.0}}}, Jp, Eigen::VectorXd::Zero(2)),
      std::invalid_argument);
  EXPECT_THROW(MarginalizationPrior::Create({{nullptr, {1.0, 2.0, 3.0}}}, Eigen::MatrixXd(0, 3),
                                            Eigen::VectorXd(0)),
               std::invalid_argument);
  EXPECT_NO_THROW(MarginalizationPrior::Create({{&quaternion, {0.0, 0.0, 0.0, 1.0}}}, Jp, r0));
}

}  // namespace
}  // namespace vio::marginalization
