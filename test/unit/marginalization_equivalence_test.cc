// The equivalence theorems of the design paper (4.3.1-4.3.5, Remark 4.3.2) on
// random linear-Gaussian problems: the reference filters (Algorithms 6-12)
// and one Gauss-Newton / marginalization step on the paper's costs agree to
// 1e-8 relative; deliberately wrong filters do not. (The same checks on
// nonlinear SE3 + landmark problems: verify_equivalence_test.cc.)
#include <ceres/manifold.h>
#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "vio/marginalization/equivalence.h"
#include "vio/marginalization/kalman_reference.h"

namespace vio::marginalization {
namespace {

constexpr double kTolerance = 1e-8;

void ExpectAgree(const EquivalenceCheck& check) {
  EXPECT_LT(check.deviation.mean, kTolerance) << "Theorem " << check.theorem << ": " << check.description;
  EXPECT_LT(check.deviation.covariance, kTolerance)
      << "Theorem " << check.theorem << ": " << check.description;
}

LinearProblemSizes Sizes(int num_features, int num_new_features, int num_poses) {
  LinearProblemSizes sizes;
  sizes.num_features = num_features;
  sizes.num_new_features = num_new_features;
  sizes.num_poses = num_poses;
  return sizes;
}

class LinearGaussianTheorems : public testing::TestWithParam<unsigned> {};

TEST_P(LinearGaussianTheorems, FilterAndOptimizationFormsAgree) {
  for (const LinearProblemSizes& sizes : {Sizes(4, 2, 4), Sizes(1, 1, 2), Sizes(12, 5, 3)}) {
    const std::vector<EquivalenceCheck> checks = CheckAll(RandomLinearGaussianProblems(sizes, GetParam()));
    ASSERT_EQ(checks.size(), 6u);
    for (const EquivalenceCheck& check : checks) ExpectAgree(check);
  }
}

INSTANTIATE_TEST_SUITE_P(Seeds, LinearGaussianTheorems, testing::Values(1u, 2u, 3u, 4u, 5u, 6u, 7u, 8u));

TEST(LinearGaussianTheorems, ChecksCoverEveryTheoremInOrder) {
  const std::vector<EquivalenceCheck> checks = CheckAll(RandomLinearGaussianProblems({}, 11));
  const std::vector<std::string> expected = {"4.3.1", "4.3.2", "4.3.3", "4.3.4", "4.3.5", "R4.3.2"};
  ASSERT_EQ(checks.size(), expected.size());
  for (size_t i = 0; i < checks.size(); ++i) EXPECT_EQ(checks[i].theorem, expected[i]);
}

TEST(LinearGaussianTheorems, StepsChangeTheState) {
  // Guards against vacuous agreement: an update moves the mean and shrinks
  // the covariance, propagation inflates it, augmentation grows the state.
  const EquivalenceProblems problems = RandomLinearGaussianProblems({}, 12);
  const EquivalenceCheck update = CheckEkfUpdate(problems.ekf_update);
  EXPECT_GT((update.filter.mean - problems.ekf_update.state.mean).norm(), 1e-3);
  EXPECT_LT(update.filter.covariance.trace(), problems.ekf_update.state.covariance.trace());
  const EquivalenceCheck msckf = CheckMsckfFeatureUpdate(problems.msckf_update);
  EXPECT_GT((msckf.filter.mean - problems.msckf_update.state.mean).norm(), 1e-3);
  EXPECT_LT(msckf.filter.covariance.trace(), problems.msckf_update.state.covariance.trace());
  const EquivalenceCheck propagation = CheckEkfPropagation(problems.ekf_propagation);
  EXPECT_GT(propagation.filter.covariance.topLeftCorner(6, 6).trace(), 0.0);
  const EquivalenceCheck augmentation = CheckEkfAugmentation(problems.ekf_augmentation);
  EXPECT_EQ(augmentation.filter.mean.size(), problems.ekf_augmentation.state.mean.size() + 6);
}

TEST(NegativeControls, WrongFiltersDoNotAgree) {
  for (unsigned seed = 1; seed <= 4; ++seed) {
    const std::vector<EquivalenceCheck> controls = NegativeControls(RandomLinearGaussianProblems({}, seed));
    ASSERT_EQ(controls.size(), 2u);
    // Without the null-space projection the triangulated features count as
    // known: a different, overconfident update.
    EXPECT_GT(controls[0].deviation.covariance, 1e-2) << controls[0].description;
    EXPECT_GT(controls[0].deviation.mean, 1e-2) << controls[0].description;
    // A Jacobian off by 1e-5 relative is caught at the 1e-8 tolerance.
    EXPECT_GT(controls[1].deviation.covariance, 10 * kTolerance) << controls[1].description;
    EXPECT_GT(controls[1].deviation.mean, 10 * kTolerance) << controls[1].description;
  }
}

TEST(NegativeControls, PerturbedPropagationJacobianDoesNotAgree) {
  PropagationProblem problem = RandomLinearGaussianProblems({}, 5).ekf_propagation;
  const Gaussian optimization = PropagationByMarginalization(problem);
  problem.dynamics.G(0, 0) += 1e-5;
  const Gaussian filter = EkfPropagate(problem.state, problem.dynamics);
  EXPECT_GT((filter.covariance - optimization.covariance).norm() / optimization.covariance.norm(),
            10 * kTolerance);
}

TEST(GaussNewtonStep, IsTheMinimizerOfTheLinearizedCost) {
  const EkfUpdateProblem problem = RandomLinearGaussianProblems({}, 21).ekf_update;
  const Gaussian step = EkfUpdateByGaussNewton(problem);
  // Rebuild the whitened cost independently and check the normal equations.
  const Eigen::Index d = problem.layout.TangentSize();
  const LinearizedCost cost =
      Whiten({{Eigen::VectorXd::Zero(d), Eigen::MatrixXd::Identity(d, d), problem.state.covariance},
              {problem.measurements.innovation, -problem.measurements.H_x, problem.measurements.Sigma_v}});
  const Eigen::VectorXd delta = step.mean - problem.state.mean;
  EXPECT_LT((cost.J.transpose() * (cost.C + cost.J * delta)).norm(), 1e-10);
  const Eigen::MatrixXd information = cost.J.transpose() * cost.J;
  EXPECT_LT((step.covariance * information - Eigen::MatrixXd::Identity(d, d)).norm(), 1e-10);
}

TEST(MarginalizationStep, EqualsTheKeptPartOfTheJointGaussNewtonStep) {
  // For a linear cost, marginalizing = the kept block of the joint solution.
  const MsckfUpdateProblem problem = RandomLinearGaussianProblems({}, 22).msckf_update;
  const Gaussian marginal = MsckfFeatureUpdateByMarginalization(problem);
  const Eigen::Index d = problem.layout.TangentSize();
  const Eigen::Index d_f = problem.feature_layout.TangentSize();
  Eigen::MatrixXd J_meas(problem.measurements.H_x.rows(), d + d_f);
  J_meas << -problem.measurements.H_x, -problem.measurements.H_f;
  Eigen::MatrixXd J_prior = Eigen::MatrixXd::Zero(d, d + d_f);
  J_prior.leftCols(d).setIdentity();
  StateLayout joint_layout = problem.layout;
  joint_layout.Append(problem.feature_layout);
  Eigen::VectorXd joint_point(d + d_f);
  joint_point << problem.state.mean, problem.feature_estimates;
  const Gaussian joint =
      GaussNewtonStep(Whiten({{Eigen::VectorXd::Zero(d), J_prior, problem.state.covariance},
                              {problem.measurements.innovation, J_meas, problem.measurements.Sigma_v}}),
                      joint_point, joint_layout);
  EXPECT_LT((marginal.mean - joint.mean.head(d)).norm(), 1e-10 * joint.mean.norm());
  EXPECT_LT((marginal.covariance - joint.covariance.topLeftCorner(d, d)).norm(),
            1e-10 * marginal.covariance.norm());
}

TEST(KalmanReference, MsckfUpdateDoesNotDependOnTheFeatureEstimate) {
  // The null-space projection removes f: for a linear model the innovation at
  // another f* changes by H_f (f*' - f*), which A^T annihilates.
  const MsckfUpdateProblem problem = RandomLinearGaussianProblems({}, 23).msckf_update;
  LinearizedMeasurements moved = problem.measurements;
  moved.innovation -= problem.measurements.H_f * Eigen::VectorXd::Ones(problem.measurements.H_f.cols());
  const Gaussian a = MsckfFeatureUpdate(problem.state, problem.layout, problem.measurements);
  const Gaussian b = MsckfFeatureUpdate(problem.state, problem.layout, moved);
  EXPECT_LT((a.mean - b.mean).norm(), 1e-10 * a.mean.norm());
  EXPECT_LT((a.covariance - b.covariance).norm(), 1e-12 * a.covariance.norm());
}

TEST(KalmanReference, PoseAugmentationCopiesThePoseAndItsCorrelations) {
  const PropagationProblem problem = RandomLinearGaussianProblems({}, 24).msckf_propagation;
  const Eigen::Index d = problem.layout.TangentSize();
  const Eigen::MatrixXd Psi = Eigen::MatrixXd::Identity(6, d);
  const Gaussian augmented = MsckfAugmentPose(problem.state, problem.state.mean.head(6), Psi);
  ASSERT_EQ(augmented.covariance.rows(), d + 6);
  EXPECT_EQ(augmented.mean.tail(6), problem.state.mean.head(6));
  EXPECT_LT((augmented.covariance.bottomRows(6).leftCols(d) - problem.state.covariance.topRows(6)).norm(),
            1e-14);
  EXPECT_LT(
      (augmented.covariance.bottomRightCorner(6, 6) - problem.state.covariance.topLeftCorner(6, 6)).norm(),
      1e-14);
}

TEST(KalmanReference, BadShapesThrowWithTheLocation) {
  const EkfUpdateProblem problem = RandomLinearGaussianProblems({}, 25).ekf_update;
  LinearizedMeasurements bad = problem.measurements;
  bad.H_x.conservativeResize(bad.H_x.rows(), bad.H_x.cols() - 1);
  try {
    EkfUpdate(problem.state, problem.layout, bad);
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("kalman_ekf.cc"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("H_x"), std::string::npos) << e.what();
  }
  LinearProblemSizes sizes;
  sizes.num_poses = 1;
  EXPECT_THROW(RandomLinearGaussianProblems(sizes, 1), std::invalid_argument);
}

TEST(StateLayout, PlusAndMinusAreInverseOverMixedBlocks) {
  const ceres::EigenQuaternionManifold quaternion;
  StateLayout layout;
  layout.AddEuclidean(2).AddManifold(&quaternion).AddEuclidean(3);
  ASSERT_EQ(layout.AmbientSize(), 9);
  ASSERT_EQ(layout.TangentSize(), 8);
  Eigen::VectorXd x(9);
  x << 1, 2, 0.5, -0.5, 0.5, 0.5, 3, 4, 5;
  Eigen::VectorXd delta(8);
  delta << 0.1, -0.2, 0.05, 0.02, -0.03, 1, 2, 3;
  const Eigen::VectorXd y = layout.Plus(x, delta);
  EXPECT_LT((layout.Minus(y, x) - delta).norm(), 1e-14);
  EXPECT_NEAR(y.segment(2, 4).norm(), 1.0, 1e-15);
  EXPECT_EQ(layout.Slice(1, 2).TangentSize(), 6);
  EXPECT_THROW(layout.Plus(x.head(8), delta), std::invalid_argument);
}

TEST(Deviation, IsRelativeToTheStepOrTheSpread) {
  StateLayout layout;
  layout.AddEuclidean(2);
  const Gaussian reference{Eigen::Vector2d(1.0, 0.0), Eigen::Matrix2d::Identity() * 4.0};
  Gaussian other = reference;
  other.mean(0) += 1e-3;
  // Step from x* = (1, 0) is zero: relative to sqrt(trace) = sqrt(8).
  EXPECT_NEAR(Compare(other, reference, layout, reference.mean).mean, 1e-3 / std::sqrt(8.0), 1e-15);
  // Step of 100 dominates.
  EXPECT_NEAR(Compare(other, reference, layout, Eigen::Vector2d(1.0, 100.0)).mean, 1e-5, 1e-15);
  other.covariance(1, 1) = 4.0 + 4e-6;
  EXPECT_NEAR(Compare(other, reference, layout, reference.mean).covariance, 4e-6 / std::sqrt(32.0), 1e-15);
}

}  // namespace
}  // namespace vio::marginalization
