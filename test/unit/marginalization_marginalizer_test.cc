// Marginalization on a live ceres::Problem: exact on linear-Gaussian problems
// (information = inverse of the kept covariance block, same minimizer), equal
// to the paper's Theorem 2.2.2 at the linearization point of a nonlinear
// problem with manifolds and a robust loss, and robust to empty blankets,
// repeated marginalization and constant blocks.
#include "vio/marginalization/marginalizer.h"

#include <map>
#include <random>
#include <stdexcept>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <ceres/autodiff_cost_function.h>
#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include "vio/marginalization/block_system.h"

namespace vio::marginalization {
namespace {

using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

double RelativeError(const Eigen::MatrixXd& actual, const Eigen::MatrixXd& expected) {
  return (actual - expected).norm() / expected.norm();
}

// r = sum_j A_j x_j - z over Euclidean blocks x_j.
class LinearResidual final : public ceres::CostFunction {
 public:
  LinearResidual(std::vector<Eigen::MatrixXd> A, Eigen::VectorXd z)
      : A_(std::move(A)), z_(std::move(z)) {
    set_num_residuals(static_cast<int>(z_.size()));
    for (const auto& A_j : A_)
      mutable_parameter_block_sizes()->push_back(static_cast<int32_t>(A_j.cols()));
  }
  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    Eigen::Map<Eigen::VectorXd> r(residuals, num_residuals());
    r = -z_;
    for (size_t j = 0; j < A_.size(); ++j) {
      r += A_[j] * Eigen::Map<const Eigen::VectorXd>(x[j], A_[j].cols());
      if (jacobians != nullptr && jacobians[j] != nullptr) {
        Eigen::Map<RowMajorMatrix>(jacobians[j], A_[j].rows(), A_[j].cols()) = A_[j];
      }
    }
    return true;
  }

 private:
  std::vector<Eigen::MatrixXd> A_;
  Eigen::VectorXd z_;
};

// A linear-Gaussian factor graph with a dense closed-form solution, and the
// same graph as a ceres::Problem over `values`.
class LinearModel {
 public:
  struct Factor {
    std::vector<int> variables;
    std::vector<Eigen::MatrixXd> A;
    Eigen::VectorXd z;
  };

  explicit LinearModel(unsigned seed) : rng_(seed) {}

  int AddVariable(int size) {
    offsets_.push_back(dim_);
    sizes_.push_back(size);
    dim_ += size;
    std::uniform_real_distribution<double> uniform(-2.0, 2.0);
    values_.emplace_back(size);
    for (double& v : values_.back())
      v = uniform(rng_);
    memory_of_.push_back(static_cast<int>(values_.size()) - 1);
    return static_cast<int>(sizes_.size()) - 1;
  }

  int AddFactor(const std::vector<int>& variables, int rows) {
    std::normal_distribution<double> normal;
    Factor factor{variables, {}, Eigen::VectorXd::NullaryExpr(rows, [&] { return normal(rng_); })};
    for (const int v : variables) {
      factor.A.push_back(
          Eigen::MatrixXd::NullaryExpr(rows, sizes_[v], [&] { return normal(rng_); }));
    }
    factors_.push_back(std::move(factor));
    return static_cast<int>(factors_.size()) - 1;
  }

  ceres::ResidualBlockId AddToProblem(int factor_index, ceres::Problem* problem) {
    const Factor& factor = factors_[factor_index];
    std::vector<double*> blocks;
    for (const int v : factor.variables)
      blocks.push_back(block(v));
    return problem->AddResidualBlock(new LinearResidual(factor.A, factor.z), nullptr, blocks);
  }

  void AddAllToProblem(ceres::Problem* problem) {
    for (size_t f = 0; f < factors_.size(); ++f)
      AddToProblem(static_cast<int>(f), problem);
  }

  // Stacked J of the given factors over all variables (r = J x - z).
  Eigen::MatrixXd Jacobian(const std::vector<int>& factors) const {
    int rows = 0;
    for (const int f : factors)
      rows += static_cast<int>(factors_[f].z.size());
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(rows, dim_);
    int row = 0;
    for (const int f : factors) {
      const Factor& factor = factors_[f];
      for (size_t j = 0; j < factor.variables.size(); ++j) {
        J.block(row, offsets_[factor.variables[j]], factor.z.size(), factor.A[j].cols()) =
            factor.A[j];
      }
      row += static_cast<int>(factor.z.size());
    }
    return J;
  }

  Eigen::VectorXd Measurements(const std::vector<int>& factors) const {
    Eigen::VectorXd z(Jacobian(factors).rows());
    int row = 0;
    for (const int f : factors) {
      z.segment(row, factors_[f].z.size()) = factors_[f].z;
      row += static_cast<int>(factors_[f].z.size());
    }
    return z;
  }

  std::vector<int> AllFactors() const {
    std::vector<int> all(factors_.size());
    for (size_t f = 0; f < all.size(); ++f)
      all[f] = static_cast<int>(f);
    return all;
  }

  // Rows of the stacked variable vector that belong to `variables`.
  std::vector<int> Indices(const std::vector<int>& variables) const {
    std::vector<int> indices;
    for (const int v : variables) {
      for (int k = 0; k < sizes_[v]; ++k)
        indices.push_back(offsets_[v] + k);
    }
    return indices;
  }

  // Exact Gaussian marginal over `kept`: information (Sigma_KK)^-1 and mean x*_K.
  void ExactMarginal(const std::vector<int>& kept, Eigen::MatrixXd* information,
                     Eigen::VectorXd* mean) const {
    const Eigen::MatrixXd J = Jacobian(AllFactors());
    const Eigen::MatrixXd H = J.transpose() * J;
    const Eigen::VectorXd x_star = H.ldlt().solve(J.transpose() * Measurements(AllFactors()));
    const Eigen::MatrixXd covariance = H.inverse();
    const std::vector<int> k = Indices(kept);
    *information = covariance(k, k).inverse();
    *mean = x_star(k);
  }

  // From now on variable v lives in the memory of variable `target` (same size).
  void ShareMemory(int v, int target) { memory_of_[v] = memory_of_[target]; }

  double* block(int v) { return values_[memory_of_[v]].data(); }
  Eigen::VectorXd Values(const std::vector<int>& variables) const {
    Eigen::VectorXd x(Indices(variables).size());
    int row = 0;
    for (const int v : variables) {
      x.segment(row, sizes_[v]) =
          Eigen::Map<const Eigen::VectorXd>(values_[memory_of_[v]].data(), sizes_[v]);
      row += sizes_[v];
    }
    return x;
  }

 private:
  std::mt19937 rng_;
  int dim_ = 0;
  std::vector<int> offsets_;
  std::vector<int> sizes_;
  std::vector<std::vector<double>> values_;
  std::vector<int> memory_of_;
  std::vector<Factor> factors_;
};

// J^T J of the whole remaining problem, columns in the order of `blocks`.
Eigen::MatrixXd ProblemInformation(ceres::Problem* problem, const std::vector<double*>& blocks) {
  ceres::Problem::EvaluateOptions options;
  options.parameter_blocks = blocks;
  ceres::CRSMatrix crs;
  EXPECT_TRUE(problem->Evaluate(options, nullptr, nullptr, nullptr, &crs));
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int row = 0; row < crs.num_rows; ++row) {
    for (int k = crs.rows[row]; k < crs.rows[row + 1]; ++k)
      J(row, crs.cols[k]) = crs.values[k];
  }
  return J.transpose() * J;
}

void Solve(ceres::Problem* problem) {
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.initial_trust_region_radius = 1e16;  // Gauss-Newton steps: exact on linear problems
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-12;  // stop once converged, before the trust region collapses
  options.parameter_tolerance = 1e-14;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, problem, &summary);
  EXPECT_TRUE(summary.IsSolutionUsable()) << summary.BriefReport();
}

// The remaining problem's information on `kept` equals the exact Gaussian
// marginal's, and solving it gives the exact marginal mean.
void ExpectExactMarginalOf(LinearModel* model, ceres::Problem* problem, const std::vector<int>& kept) {
  Eigen::MatrixXd exact_information;
  Eigen::VectorXd exact_mean;
  model->ExactMarginal(kept, &exact_information, &exact_mean);
  std::vector<double*> kept_blocks;
  for (const int v : kept)
    kept_blocks.push_back(model->block(v));
  EXPECT_LT(RelativeError(ProblemInformation(problem, kept_blocks), exact_information), 1e-9);
  Solve(problem);
  EXPECT_LT(RelativeError(model->Values(kept), exact_mean), 1e-9);
}

// Five chained Euclidean blocks with a loop factor; blocks 0 and 1 go.
class LinearChainTest : public ::testing::Test {
 protected:
  LinearChainTest() : model_(42) {
    for (const int size : {2, 3, 2, 3, 2})
      model_.AddVariable(size);
    model_.AddFactor({0}, 3);
    model_.AddFactor({0, 1}, 4);
    model_.AddFactor({1, 2}, 4);
    model_.AddFactor({1, 2, 3}, 5);
    model_.AddFactor({2, 3}, 3);
    model_.AddFactor({3, 4}, 3);
    model_.AddFactor({4}, 2);
    model_.AddFactor({0, 3}, 3);
    model_.AddAllToProblem(&problem_);
    model_.ExactMarginal(kept_, &exact_information_, &exact_mean_);
  }

  std::vector<double*> KeptBlocks() { return {model_.block(2), model_.block(3), model_.block(4)}; }

  void ExpectExactMarginal() {
    EXPECT_EQ(problem_.NumParameterBlocks(), 3);
    EXPECT_LT(RelativeError(ProblemInformation(&problem_, KeptBlocks()), exact_information_), 1e-9);
    Solve(&problem_);
    EXPECT_LT(RelativeError(model_.Values(kept_), exact_mean_), 1e-9);
  }

  LinearModel model_;
  ceres::Problem problem_;
  const std::vector<int> kept_ = {2, 3, 4};
  Eigen::MatrixXd exact_information_;
  Eigen::VectorXd exact_mean_;
};

TEST_F(LinearChainTest, MarginalEqualsExactGaussianMarginal) {
  EXPECT_NE(MarginalizeBlocks(&problem_, {model_.block(0), model_.block(1)}), nullptr);
  ExpectExactMarginal();
}

TEST_F(LinearChainTest, MarginalizeThenSolveEqualsSolveThenDropOnTheKeptVariables) {
  // Same graph, same start, no marginalization.
  LinearModel full_model(42);
  for (const int size : {2, 3, 2, 3, 2})
    full_model.AddVariable(size);
  for (const auto& [variables, rows] : std::vector<std::pair<std::vector<int>, int>>{{{0}, 3},
                                                                                     {{0, 1}, 4},
                                                                                     {{1, 2}, 4},
                                                                                     {{1, 2, 3}, 5},
                                                                                     {{2, 3}, 3},
                                                                                     {{3, 4}, 3},
                                                                                     {{4}, 2},
                                                                                     {{0, 3}, 3}}) {
    full_model.AddFactor(variables, rows);
  }
  ceres::Problem full_problem;
  full_model.AddAllToProblem(&full_problem);
  Solve(&full_problem);

  MarginalizeBlocks(&problem_, {model_.block(0), model_.block(1)});
  Solve(&problem_);
  EXPECT_LT(RelativeError(model_.Values(kept_), full_model.Values(kept_)), 1e-9);
}

TEST_F(LinearChainTest, SequentialMarginalizationChainsPriors) {
  // Block 1 is in the first prior's blanket: the second marginalization folds
  // that prior (evaluated away from nothing: still at x0) into the new one.
  EXPECT_NE(MarginalizeBlocks(&problem_, {model_.block(0)}), nullptr);
  EXPECT_NE(MarginalizeBlocks(&problem_, {model_.block(1)}), nullptr);
  ExpectExactMarginal();
}

TEST_F(LinearChainTest, MarginalizationAwayFromTheOptimumIsStillExact) {
  Solve(&problem_);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uniform(-5.0, 5.0);
  for (const int v : {0, 1, 2, 3, 4}) {
    for (int k = 0; k < 2; ++k)
      model_.block(v)[k] += uniform(rng);
  }
  MarginalizeBlocks(&problem_, {model_.block(1), model_.block(0)});
  ExpectExactMarginal();
}

TEST_F(LinearChainTest, ComputeMarginalizationLeavesTheProblemUnchanged) {
  const MarginalizationResult result =
      ComputeMarginalization(&problem_, {model_.block(0), model_.block(1), model_.block(0)});
  ASSERT_NE(result.prior, nullptr);
  EXPECT_EQ(problem_.NumParameterBlocks(), 5);
  EXPECT_EQ(problem_.NumResidualBlocks(), 8);
  EXPECT_EQ(result.marginalized_residual_blocks.size(), 5u);  // all but {2,3}, {3,4}, {4}
  EXPECT_EQ(result.kept_blocks.size(), 2u);                   // blocks 2 and 3
  EXPECT_EQ(result.prior->sqrt_information().cols(), 2 + 3);
}

// kept_order puts the listed kept blocks first, in its order; the prior is
// the same marginal with its columns permuted.
TEST_F(LinearChainTest, KeptOrderOrdersThePriorsBlocks) {
  const std::vector<double*> marginalized = {model_.block(0), model_.block(1)};
  const MarginalizationResult by_appearance = ComputeMarginalization(&problem_, marginalized);
  ASSERT_EQ(by_appearance.kept_blocks, (std::vector<double*>{model_.block(2), model_.block(3)}));
  MarginalizationOptions options;
  options.kept_order = {model_.block(4), model_.block(3)};  // block 4 is not kept: skipped
  const MarginalizationResult ordered = ComputeMarginalization(&problem_, marginalized, options);
  ASSERT_EQ(ordered.kept_blocks, (std::vector<double*>{model_.block(3), model_.block(2)}));
  Eigen::MatrixXd permuted(5, 5);  // block 3 (3 columns) first, then block 2 (2)
  const Eigen::MatrixXd& H = by_appearance.prior->information();
  permuted << H.block(2, 2, 3, 3), H.block(2, 0, 3, 2), H.block(0, 2, 2, 3), H.block(0, 0, 2, 2);
  EXPECT_LT(RelativeError(ordered.prior->information(), permuted), 1e-12);
}

// FEJ: a kept block with a first estimate (given along kept_order) gets its prior re-expressed
// there, x0 = x_fe and r0 + Jp (x_fe - x): on this linear model the same residual at the current
// values; a block without one keeps the current values. first_estimates must be as long as kept_order.
TEST_F(LinearChainTest, FirstEstimatesAlongKeptOrderReexpressThePrior) {
  const std::vector<double*> marginalized = {model_.block(0), model_.block(1)};
  MarginalizationOptions options;
  options.kept_order = {model_.block(3), model_.block(2)};
  const MarginalizationResult current = ComputeMarginalization(&problem_, marginalized, options);
  const std::vector<double> first = {model_.block(3)[0] + 0.5, model_.block(3)[1] - 0.25, model_.block(3)[2] + 1.0};
  options.first_estimates = {first.data(), nullptr};
  const MarginalizationResult held = ComputeMarginalization(&problem_, marginalized, options);
  ASSERT_NE(current.prior, nullptr);
  ASSERT_NE(held.prior, nullptr);
  EXPECT_EQ(held.prior->linearization_point(0), first);
  EXPECT_EQ(held.prior->linearization_point(1), current.prior->linearization_point(1));
  EXPECT_TRUE(held.prior->jacobian_at_linearization_point());
  const auto residual_at_current = [&](const MarginalizationPrior& prior) {
    const double* values[] = {model_.block(3), model_.block(2)};
    Eigen::VectorXd r(prior.num_residuals());
    EXPECT_TRUE(prior.Evaluate(values, r.data(), nullptr));
    return r;
  };
  EXPECT_LT((residual_at_current(*held.prior) - residual_at_current(*current.prior)).norm(), 1e-9);
  options.first_estimates = {first.data()};
  EXPECT_THROW(ComputeMarginalization(&problem_, marginalized, options), std::invalid_argument);
}

TEST_F(LinearChainTest, BlockNotInTheProblemIsRejected) {
  double stranger[2] = {0.0, 0.0};
  EXPECT_THROW(ComputeMarginalization(&problem_, {stranger}), std::invalid_argument);
  EXPECT_THROW(MarginalizeBlocks(&problem_, {model_.block(0), stranger}), std::invalid_argument);
  EXPECT_EQ(problem_.NumParameterBlocks(), 5);
}

// Frames observe landmarks; a frame and the landmarks it sees are
// marginalized together (landmarks take the block-by-block path).
TEST(MarginalizeBlocks, FrameWithItsLandmarksIsExact) {
  LinearModel model(9);
  const int f0 = model.AddVariable(6), f1 = model.AddVariable(6), f2 = model.AddVariable(6);
  std::vector<int> landmarks;
  for (int j = 0; j < 6; ++j)
    landmarks.push_back(model.AddVariable(3));
  model.AddFactor({f0}, 6);
  model.AddFactor({f0, f1}, 6);
  model.AddFactor({f1, f2}, 6);
  for (int j = 0; j < 6; ++j) {
    const std::vector<int> seen_by =
        j < 3 ? std::vector<int>{f0, f1, f2} : std::vector<int>{f1, f2};
    for (const int frame : seen_by)
      model.AddFactor({frame, landmarks[j]}, 2);
  }
  ceres::Problem problem;
  model.AddAllToProblem(&problem);
  MarginalizeBlocks(&problem, {model.block(f0), model.block(landmarks[0]),
                               model.block(landmarks[1]), model.block(landmarks[2])});
  ExpectExactMarginalOf(&model, &problem, {f1, f2, landmarks[3], landmarks[4], landmarks[5]});
}

// A prior wide enough that its rows take the dense path (more than 64
// nonzeros: it spans five 15-dimensional frames) is folded into the next
// marginalization, whose blanket also holds landmarks the prior does not
// touch: the dense product covers only the prior's columns.
TEST(MarginalizeBlocks, WidePriorFoldedIntoABlanketWithLandmarksIsExact) {
  LinearModel model(17);
  std::vector<int> frames;
  for (int i = 0; i < 6; ++i)
    frames.push_back(model.AddVariable(15));
  std::vector<int> landmarks;
  for (int j = 0; j < 8; ++j)
    landmarks.push_back(model.AddVariable(3));
  model.AddFactor({frames[0]}, 15);
  for (int i = 0; i + 1 < 6; ++i)
    model.AddFactor({frames[i], frames[i + 1]}, 15);
  model.AddFactor({frames[0], frames[2], frames[3], frames[4], frames[5]}, 20);
  for (int j = 0; j < 8; ++j) {
    for (const int frame : {frames[1], frames[j % 2 == 0 ? 3 : 5]})
      model.AddFactor({frame, landmarks[j]}, 3);
  }
  ceres::Problem problem;
  model.AddAllToProblem(&problem);
  std::vector<int> kept = {frames[2], frames[3], frames[4], frames[5]};
  kept.insert(kept.end(), landmarks.begin(), landmarks.end());
  const ceres::ResidualBlockId wide = MarginalizeBlocks(&problem, {model.block(frames[0])});
  ASSERT_NE(wide, nullptr);
  std::vector<double*> spanned;
  problem.GetParameterBlocksForResidualBlock(wide, &spanned);
  ASSERT_EQ(spanned.size(), 5u);  // frames 1-5: 75 columns, a dense row
  MarginalizeBlocks(&problem, {model.block(frames[1])});
  ExpectExactMarginalOf(&model, &problem, kept);
}

// The second marginalization eliminates frame 1's 6-dimensional block by
// itself (the smallest block, coupled to no other marginalized one but its
// 9-dimensional partner, which is eliminated densely) while the first prior
// involves it: the prior's information enters that block's own part of the
// normal equations (BlockSystem's AddPrior), and the marginal stays exact.
TEST(MarginalizeBlocks, PriorOnABlockEliminatedByItselfIsExact) {
  LinearModel model(23);
  std::vector<int> poses, speeds, landmarks;
  for (int i = 0; i < 3; ++i) {
    poses.push_back(model.AddVariable(6));
    speeds.push_back(model.AddVariable(9));
  }
  for (int j = 0; j < 4; ++j)
    landmarks.push_back(model.AddVariable(3));
  model.AddFactor({poses[0], speeds[0]}, 15);
  for (int i = 0; i + 1 < 3; ++i)
    model.AddFactor({poses[i], speeds[i], poses[i + 1], speeds[i + 1]}, 15);
  for (int j = 0; j < 4; ++j) {
    for (const int pose : poses)
      model.AddFactor({pose, landmarks[j]}, 3);
  }
  ceres::Problem problem;
  model.AddAllToProblem(&problem);
  ASSERT_NE(MarginalizeBlocks(&problem, {model.block(poses[0]), model.block(speeds[0])}), nullptr);
  ASSERT_NE(MarginalizeBlocks(&problem, {model.block(poses[1]), model.block(speeds[1])}), nullptr);
  std::vector<int> kept = {poses[2], speeds[2]};
  kept.insert(kept.end(), landmarks.begin(), landmarks.end());
  ExpectExactMarginalOf(&model, &problem, kept);
}

TEST(MarginalizeBlocks, EmptyBlanketRemovesTheBlockAndAddsNoPrior) {
  LinearModel model(1);
  const int a = model.AddVariable(2), b = model.AddVariable(3);
  model.AddFactor({a}, 2);
  model.AddFactor({b}, 3);
  ceres::Problem problem;
  model.AddAllToProblem(&problem);
  double lonely[2] = {1.0, 2.0};
  problem.AddParameterBlock(lonely, 2);

  EXPECT_EQ(MarginalizeBlocks(&problem, {model.block(a)}), nullptr);
  EXPECT_EQ(MarginalizeBlocks(&problem, {lonely}), nullptr);
  EXPECT_FALSE(problem.HasParameterBlock(model.block(a)));
  EXPECT_FALSE(problem.HasParameterBlock(lonely));
  EXPECT_TRUE(problem.HasParameterBlock(model.block(b)));
  EXPECT_EQ(problem.NumResidualBlocks(), 1);
}

TEST(MarginalizeBlocks, SameBlockTwiceAfterReAddingIt) {
  // a is marginalized, re-added with new factors (a new variable a' in the
  // same memory), and marginalized again: the two priors together are the
  // exact marginal of a graph with a and a' as distinct variables.
  LinearModel model(5);
  const int a = model.AddVariable(2), b = model.AddVariable(3), c = model.AddVariable(2);
  const int a_again = model.AddVariable(2);
  const std::vector<int> first = {model.AddFactor({a}, 2), model.AddFactor({a, b}, 3),
                                  model.AddFactor({b, c}, 3), model.AddFactor({c}, 2)};
  const std::vector<int> second = {model.AddFactor({a_again, b}, 3), model.AddFactor({a_again}, 2)};
  ceres::Problem problem;
  for (const int f : first)
    model.AddToProblem(f, &problem);
  ASSERT_NE(MarginalizeBlocks(&problem, {model.block(a)}), nullptr);

  model.ShareMemory(a_again, a);  // re-added at the same address
  for (const int f : second)
    model.AddToProblem(f, &problem);
  ASSERT_TRUE(problem.HasParameterBlock(model.block(a)));
  ASSERT_NE(MarginalizeBlocks(&problem, {model.block(a)}), nullptr);
  EXPECT_EQ(problem.NumResidualBlocks(), 2 + 2);  // {b,c}, {c}, two priors

  Eigen::MatrixXd exact_information;
  Eigen::VectorXd exact_mean;
  model.ExactMarginal({b, c}, &exact_information, &exact_mean);
  EXPECT_LT(RelativeError(ProblemInformation(&problem, {model.block(b), model.block(c)}),
                          exact_information),
            1e-9);
  Solve(&problem);
  EXPECT_LT(RelativeError(model.Values({b, c}), exact_mean), 1e-9);
}

// The marginal of Theorem 2.2.2 with the projector P = I - J_M (J_M^T J_M)^-1 J_M^T:
// information J_K^T P J_K and information vector J_K^T P C2.
NormalEquations PaperMarginal(const Eigen::MatrixXd& J_K, const Eigen::MatrixXd& J_M,
                              const Eigen::VectorXd& C2) {
  const Eigen::MatrixXd P = Eigen::MatrixXd::Identity(J_M.rows(), J_M.rows()) -
                            J_M * (J_M.transpose() * J_M).inverse() * J_M.transpose();
  return {J_K.transpose() * P * J_K, J_K.transpose() * P * C2};
}

void ExpectPriorMatches(const MarginalizationPrior& prior, const NormalEquations& expected) {
  const Eigen::MatrixXd& Jp = prior.sqrt_information();
  EXPECT_LT(RelativeError(Jp.transpose() * Jp, expected.H), 1e-9);
  EXPECT_LT(RelativeError(Jp.transpose() * prior.residual_at_x0(), expected.b), 1e-9);
}

TEST(MarginalizeBlocks, ConstantBlanketBlockIsKnownAndLeftOutOfThePrior) {
  LinearModel model(8);
  const int a = model.AddVariable(2), k1 = model.AddVariable(2), k2 = model.AddVariable(3);
  const std::vector<int> c2 = {model.AddFactor({a, k1, k2}, 4), model.AddFactor({a}, 2)};
  model.AddFactor({k1, k2}, 3);
  ceres::Problem problem;
  model.AddAllToProblem(&problem);
  problem.SetParameterBlockConstant(model.block(k1));

  const MarginalizationResult result = ComputeMarginalization(&problem, {model.block(a)});
  ASSERT_NE(result.prior, nullptr);
  ASSERT_EQ(result.kept_blocks, std::vector<double*>{model.block(k2)});
  const Eigen::MatrixXd J = model.Jacobian(c2);
  const Eigen::VectorXd C2 = J * model.Values({a, k1, k2}) - model.Measurements(c2);
  ExpectPriorMatches(*result.prior, PaperMarginal(J(Eigen::all, model.Indices({k2})),
                                                  J(Eigen::all, model.Indices({a})), C2));

  EXPECT_NE(MarginalizeBlocks(&problem, {model.block(a)}), nullptr);
  EXPECT_TRUE(problem.IsParameterBlockConstant(model.block(k1)));
  EXPECT_EQ(problem.NumResidualBlocks(), 2);
}

TEST(MarginalizeBlocks, ConstantMarginalizedBlockIsConditionedOn) {
  LinearModel model(8);
  const int a = model.AddVariable(2), k1 = model.AddVariable(2), k2 = model.AddVariable(3);
  const std::vector<int> c2 = {model.AddFactor({a, k1, k2}, 4), model.AddFactor({a}, 2)};
  model.AddFactor({k1, k2}, 3);
  ceres::Problem problem;
  model.AddAllToProblem(&problem);
  problem.SetParameterBlockConstant(model.block(a));

  const MarginalizationResult result = ComputeMarginalization(&problem, {model.block(a)});
  ASSERT_NE(result.prior, nullptr);
  ASSERT_EQ(result.kept_blocks.size(), 2u);
  const Eigen::MatrixXd J_K = model.Jacobian(c2)(Eigen::all, model.Indices({k1, k2}));
  const Eigen::VectorXd C2 =
      model.Jacobian(c2) * model.Values({a, k1, k2}) - model.Measurements(c2);
  ExpectPriorMatches(*result.prior, {J_K.transpose() * J_K, J_K.transpose() * C2});
}

TEST(MarginalizeBlocks, AllConstantBlanketGivesNoPrior) {
  LinearModel model(2);
  const int a = model.AddVariable(2), k = model.AddVariable(2);
  model.AddFactor({a, k}, 3);
  ceres::Problem problem;
  model.AddAllToProblem(&problem);
  problem.SetParameterBlockConstant(model.block(k));
  EXPECT_EQ(MarginalizeBlocks(&problem, {model.block(a)}), nullptr);
  EXPECT_EQ(problem.NumResidualBlocks(), 0);
  EXPECT_TRUE(problem.HasParameterBlock(model.block(k)));
}

// A window's shape: poses p0..p3, then speed/bias blocks s0..s3 chained by
// (p_i, s_i, p_i+1, s_i+1) factors, and a prior-like factor tying s0 to every
// pose. Counting only the poses, a speed/bias block spans the poses its
// factors touch, not every column up to its right neighbour.
TEST(BlockSystem, CoupledSpansOverTheCountedBlocksOnly) {
  LinearModel model(5);
  std::vector<int> poses, speeds;
  for (int i = 0; i < 4; ++i) poses.push_back(model.AddVariable(6));
  for (int i = 0; i < 4; ++i) speeds.push_back(model.AddVariable(9));
  for (int i = 0; i + 1 < 4; ++i) model.AddFactor({poses[i], speeds[i], poses[i + 1], speeds[i + 1]}, 15);
  model.AddFactor({speeds[0], poses[0], poses[1], poses[2], poses[3]}, 9);
  ceres::Problem problem;
  model.AddAllToProblem(&problem);
  BlockLayout layout;
  for (const int v : poses) layout.dense.push_back(model.block(v));
  for (const int v : speeds) layout.dense.push_back(model.block(v));
  problem.GetResidualBlocks(&layout.residuals);
  const BlockSystem system(&problem, layout);
  using Span = std::pair<int, int>;
  const std::vector<Span> all = system.CoupledSpans();
  EXPECT_EQ(all[5], Span(0, 6));  // s1: p0 .. s2
  EXPECT_EQ(all[4], Span(0, 5));  // s0: p0 .. s1
  const std::vector<bool> poses_only = {true, true, true, true, false, false, false, false};
  const std::vector<Span> over_poses = system.CoupledSpans(poses_only);
  EXPECT_EQ(over_poses[4], Span(0, 3));  // s0: every pose (the prior-like factor)
  EXPECT_EQ(over_poses[5], Span(0, 2));  // s1: p0 .. p2
  EXPECT_EQ(over_poses[7], Span(2, 3));
  EXPECT_EQ(over_poses[1], Span(0, 3));
}

// Nonlinear factors on poses (q_w_b, p_w_b) with quaternion manifolds.

// r = R(q_w_b)^T (p_w_l - p_w_b) - p_b_l_measured: a landmark seen from a pose.
struct LandmarkInBodyResidual {
  template <typename T>
  bool operator()(const T* q, const T* p, const T* landmark, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q_w_b(q);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_w_b(p), p_w_l(landmark);
    Eigen::Map<Eigen::Matrix<T, 3, 1>> r(residual);
    r = q_w_b.conjugate() * (p_w_l - p_w_b) - p_b_l.cast<T>();
    return true;
  }
  static ceres::CostFunction* Create(const Eigen::Vector3d& p_b_l) {
    return new ceres::AutoDiffCostFunction<LandmarkInBodyResidual, 3, 4, 3, 3>(
        new LandmarkInBodyResidual{p_b_l});
  }
  Eigen::Vector3d p_b_l;
};

// r = [R_a^T (p_b - p_a) - p_a_b; 2 vec(q_a_b_measured^-1 q_a^-1 q_b)]: relative pose.
struct RelativePoseResidual {
  template <typename T>
  bool operator()(const T* qa, const T* pa, const T* qb, const T* pb, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q_w_a(qa), q_w_b(qb);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p_w_a(pa), p_w_b(pb);
    Eigen::Map<Eigen::Matrix<T, 6, 1>> r(residual);
    r.template head<3>() = q_w_a.conjugate() * (p_w_b - p_w_a) - p_a_b.cast<T>();
    r.template tail<3>() = T(2.0) * (q_a_b.cast<T>().conjugate() * q_w_a.conjugate() * q_w_b).vec();
    return true;
  }
  static ceres::CostFunction* Create(const Eigen::Vector3d& p_a_b,
                                     const Eigen::Quaterniond& q_a_b) {
    return new ceres::AutoDiffCostFunction<RelativePoseResidual, 6, 4, 3, 4, 3>(
        new RelativePoseResidual{p_a_b, q_a_b});
  }
  Eigen::Vector3d p_a_b;
  Eigen::Quaterniond q_a_b;
};

// r = [p_w_b - p_measured; 2 vec(q_measured^-1 q_w_b)]: absolute pose prior.
struct PosePriorResidual {
  template <typename T>
  bool operator()(const T* q, const T* p, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q_w_b(q);
    Eigen::Map<Eigen::Matrix<T, 6, 1>> r(residual);
    r.template head<3>() = Eigen::Map<const Eigen::Matrix<T, 3, 1>>(p) - p_w_b.cast<T>();
    r.template tail<3>() = T(2.0) * (q_measured.cast<T>().conjugate() * q_w_b).vec();
    return true;
  }
  static ceres::CostFunction* Create(const Eigen::Vector3d& p_w_b, const Eigen::Quaterniond& q) {
    return new ceres::AutoDiffCostFunction<PosePriorResidual, 6, 4, 3>(
        new PosePriorResidual{p_w_b, q});
  }
  Eigen::Vector3d p_w_b;
  Eigen::Quaterniond q_measured;
};

class NonlinearPosesTest : public ::testing::Test {
 protected:
  void SetUp() override {
    Eigen::Map<Eigen::Quaterniond> q_w_0(q0_), q_w_1(q1_);
    q_w_0 = Eigen::Quaterniond(0.9, 0.1, -0.3, 0.2).normalized();
    q_w_1 = Eigen::Quaterniond(0.8, -0.2, 0.1, 0.4).normalized();
    const Eigen::Quaterniond q_noise = Eigen::Quaterniond(1.0, 0.05, -0.04, 0.03).normalized();
    for (double* q : {q0_, q1_})
      problem_.AddParameterBlock(q, 4, new ceres::EigenQuaternionManifold);
    ids_.push_back(problem_.AddResidualBlock(
        PosePriorResidual::Create({0.1, 0.2, -0.1}, q_noise * q_w_0), nullptr, q0_, p0_));
    ids_.push_back(problem_.AddResidualBlock(LandmarkInBodyResidual::Create({1.0, 4.0, -2.0}),
                                             new ceres::CauchyLoss(0.5), q0_, p0_, l0_));
    ids_.push_back(problem_.AddResidualBlock(LandmarkInBodyResidual::Create({-3.0, 1.0, 2.5}),
                                             nullptr, q0_, p0_, l1_));
    ids_.push_back(problem_.AddResidualBlock(RelativePoseResidual::Create({1.2, 0.9, 0.1}, q_noise),
                                             nullptr, q0_, p0_, q1_, p1_));
    problem_.AddResidualBlock(LandmarkInBodyResidual::Create({0.5, 2.0, -1.0}), nullptr, q1_, p1_,
                              l0_);
  }

  // Tangent-space Jacobian columns of `blocks` and residuals of ids_, assembled
  // one residual block at a time (independently of Problem::Evaluate).
  void Assemble(const std::vector<double*>& kept, const std::vector<double*>& marg,
                Eigen::MatrixXd* J_K, Eigen::MatrixXd* J_M, Eigen::VectorXd* C2) {
    std::map<double*, std::pair<Eigen::MatrixXd*, int>> column_of;
    int cols_K = 0, cols_M = 0;
    for (double* block : kept)
      column_of[block] = {
          J_K, std::exchange(cols_K, cols_K + problem_.ParameterBlockTangentSize(block))};
    for (double* block : marg)
      column_of[block] = {
          J_M, std::exchange(cols_M, cols_M + problem_.ParameterBlockTangentSize(block))};
    int rows = 0;
    for (const auto id : ids_)
      rows += problem_.GetCostFunctionForResidualBlock(id)->num_residuals();
    *J_K = Eigen::MatrixXd::Zero(rows, cols_K);
    *J_M = Eigen::MatrixXd::Zero(rows, cols_M);
    C2->resize(rows);
    int row = 0;
    for (const auto id : ids_) {
      std::vector<double*> blocks;
      problem_.GetParameterBlocksForResidualBlock(id, &blocks);
      const int n = problem_.GetCostFunctionForResidualBlock(id)->num_residuals();
      std::vector<RowMajorMatrix> jacobians;
      for (double* block : blocks)
        jacobians.emplace_back(n, problem_.ParameterBlockTangentSize(block));
      std::vector<double*> jacobian_ptrs;
      for (auto& jacobian : jacobians)
        jacobian_ptrs.push_back(jacobian.data());
      double cost = 0.0;
      ASSERT_TRUE(
          problem_.EvaluateResidualBlock(id, true, &cost, C2->data() + row, jacobian_ptrs.data()));
      for (size_t j = 0; j < blocks.size(); ++j) {
        const auto [matrix, col] = column_of.at(blocks[j]);
        matrix->block(row, col, n, jacobians[j].cols()) = jacobians[j];
      }
      row += n;
    }
  }

  double q0_[4], q1_[4];
  double p0_[3] = {0.0, 0.1, 0.2}, p1_[3] = {1.0, 1.1, 0.4};
  double l0_[3] = {2.0, 3.0, -1.0}, l1_[3] = {-2.0, 0.5, 3.0};
  ceres::Problem problem_;
  std::vector<ceres::ResidualBlockId> ids_;  // the residual blocks touching (q0, p0)
};

TEST_F(NonlinearPosesTest, PriorAtTheLinearizationPointIsTheoremTwoTwoTwo) {
  for (const SqrtMethod method : {SqrtMethod::kEigen, SqrtMethod::kPivotedCholesky, SqrtMethod::kPivotedCholeskyOnly}) {
    SCOPED_TRACE(static_cast<int>(method));
    MarginalizationOptions options;
    options.sqrt_method = method;
    const MarginalizationResult result = ComputeMarginalization(&problem_, {q0_, p0_}, options);
    ASSERT_NE(result.prior, nullptr);
    EXPECT_EQ(result.marginalized_residual_blocks, ids_);
    EXPECT_EQ(result.kept_blocks, (std::vector<double*>{l0_, l1_, q1_, p1_}));

    Eigen::MatrixXd J_K, J_M;
    Eigen::VectorXd C2;
    Assemble(result.kept_blocks, {q0_, p0_}, &J_K, &J_M, &C2);
    ExpectPriorMatches(*result.prior, PaperMarginal(J_K, J_M, C2));

    // x0 is a copy of the current values, the manifold is the problem's.
    const MarginalizationPrior::Block& q1_block = result.prior->blocks()[2];
    EXPECT_EQ(q1_block.manifold, problem_.GetManifold(q1_));
    EXPECT_EQ(q1_block.x0, std::vector<double>(q1_, q1_ + 4));
  }
}

TEST_F(NonlinearPosesTest, PriorInTheProblemEvaluatesToR0AndJpAtX0) {
  ceres::ResidualBlockId prior_id = MarginalizeBlocks(&problem_, {q0_, p0_});
  ASSERT_NE(prior_id, nullptr);
  const auto* prior =
      dynamic_cast<const MarginalizationPrior*>(problem_.GetCostFunctionForResidualBlock(prior_id));
  ASSERT_NE(prior, nullptr);
  const int rows = prior->num_residuals();
  EXPECT_EQ(rows, 3 + 3 + 3 + 3);  // full rank on (l0, l1, q1, p1)

  std::vector<RowMajorMatrix> jacobians;
  std::vector<double*> jacobian_ptrs;
  for (int i = 0; i < 4; ++i)
    jacobians.emplace_back(rows, prior->tangent_size(i));
  for (auto& jacobian : jacobians)
    jacobian_ptrs.push_back(jacobian.data());
  Eigen::VectorXd residual(rows);
  double cost = 0.0;
  ASSERT_TRUE(problem_.EvaluateResidualBlock(prior_id, false, &cost, residual.data(),
                                             jacobian_ptrs.data()));
  EXPECT_LT(RelativeError(residual, prior->residual_at_x0()), 1e-14);
  for (int i = 0; i < 4; ++i) {
    EXPECT_LT(RelativeError(jacobians[i], prior->sqrt_information().middleCols(
                                              prior->tangent_offset(i), prior->tangent_size(i))),
              1e-12)
        << "block " << i;
  }
}

TEST_F(NonlinearPosesTest, SolvingAfterMarginalizationConverges) {
  MarginalizeBlocks(&problem_, {q0_, p0_});
  ceres::Solver::Options options;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem_, &summary);
  EXPECT_EQ(summary.termination_type, ceres::CONVERGENCE) << summary.BriefReport();
  EXPECT_LE(summary.final_cost, summary.initial_cost);
  EXPECT_NEAR(Eigen::Map<Eigen::Quaterniond>(q1_).norm(), 1.0, 1e-12);
}

}  // namespace
}  // namespace vio::marginalization
