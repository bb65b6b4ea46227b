// Dense marginalization algebra against closed forms: the Schur complement is
// the inverse of the kept block of the covariance and keeps the kept part of
// the minimizer; the square root reproduces (H, b).
#include "vio/marginalization/linear_algebra.h"

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>
#include <gtest/gtest.h>

namespace vio::marginalization {
namespace {

double RelativeError(const Eigen::MatrixXd& actual, const Eigen::MatrixXd& expected) {
  return (actual - expected).norm() / expected.norm();
}

Eigen::MatrixXd RandomMatrix(int rows, int cols, std::mt19937* rng) {
  std::normal_distribution<double> normal;
  return Eigen::MatrixXd::NullaryExpr(rows, cols, [&] { return normal(*rng); });
}

// H = J^T J and b = J^T r of a random over-determined linear cost.
NormalEquations RandomNormalEquations(int rows, int dim, std::mt19937* rng) {
  const Eigen::MatrixXd J = RandomMatrix(rows, dim, rng);
  const Eigen::VectorXd r = RandomMatrix(rows, 1, rng);
  return {J.transpose() * J, J.transpose() * r};
}

TEST(AllFinite, AgreesWithEigensAllFinite) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double largest = std::numeric_limits<double>::max();
  for (const double value : {0.0, -0.0, 1.0, -largest, largest, std::numeric_limits<double>::denorm_min(), inf, -inf,
                             nan}) {
    Eigen::MatrixXd m = Eigen::MatrixXd::Constant(7, 5, largest);  // sums of such overflow; their products by 0 do not
    m(3, 2) = value;
    EXPECT_EQ(AllFinite(m), m.allFinite()) << value;
    Eigen::VectorXd v = Eigen::VectorXd::Ones(9);
    v[8] = value;
    EXPECT_EQ(AllFinite(v), v.allFinite()) << value;
  }
  EXPECT_TRUE(AllFinite(Eigen::MatrixXd(0, 0)));
}

TEST(SchurComplement, EqualsInverseOfMarginalCovarianceAndKeepsTheMinimizer) {
  std::mt19937 rng(1);
  const int keep = 4, marg = 5;
  const NormalEquations full = RandomNormalEquations(20, keep + marg, &rng);
  const NormalEquations marginal = SchurComplement(full.H, full.b, keep, marg);

  const Eigen::MatrixXd covariance = full.H.inverse();
  const Eigen::MatrixXd expected_information = covariance.topLeftCorner(keep, keep).inverse();
  EXPECT_LT(RelativeError(marginal.H, expected_information), 1e-10);

  // argmin of dx^T H dx + 2 b^T dx is -H^-1 b; its kept part is the marginal's argmin.
  const Eigen::VectorXd full_minimizer = -full.H.ldlt().solve(full.b);
  const Eigen::VectorXd marginal_minimizer = -marginal.H.ldlt().solve(marginal.b);
  EXPECT_LT(RelativeError(marginal_minimizer, full_minimizer.head(keep)), 1e-10);
}

TEST(SchurComplement, NothingToMarginalizeReturnsTheInput) {
  std::mt19937 rng(2);
  const NormalEquations full = RandomNormalEquations(8, 3, &rng);
  const NormalEquations marginal = SchurComplement(full.H, full.b, 3, 0);
  EXPECT_LT(RelativeError(marginal.H, full.H), 1e-15);
  EXPECT_LT(RelativeError(marginal.b, full.b), 1e-15);
}

TEST(SchurComplement, UnconstrainedMarginalizedDirectionIsDropped) {
  // The last variable appears in no residual: H_MM is singular. The
  // pseudo-inverse must give the same marginal as if it did not exist.
  std::mt19937 rng(3);
  const int keep = 3, marg = 3;
  NormalEquations with_free = RandomNormalEquations(12, keep + marg, &rng);
  with_free.H.row(keep + marg - 1).setZero();
  with_free.H.col(keep + marg - 1).setZero();
  with_free.b(keep + marg - 1) = 0.0;
  const NormalEquations expected =
      SchurComplement(with_free.H.topLeftCorner(5, 5), with_free.b.head(5), keep, 2);
  const NormalEquations actual = SchurComplement(with_free.H, with_free.b, keep, marg);
  EXPECT_LT(RelativeError(actual.H, expected.H), 1e-10);
  EXPECT_LT(RelativeError(actual.b, expected.b), 1e-10);
}

TEST(SchurComplement, RejectsInconsistentSizes) {
  const Eigen::MatrixXd H = Eigen::MatrixXd::Identity(4, 4);
  const Eigen::VectorXd b = Eigen::VectorXd::Zero(4);
  EXPECT_THROW(SchurComplement(H, b, 2, 1), std::invalid_argument);
  EXPECT_THROW(SchurComplement(H, Eigen::VectorXd::Zero(3), 2, 2), std::invalid_argument);
  Eigen::MatrixXd not_finite = H;
  not_finite(1, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(SchurComplement(not_finite, b, 2, 2), std::invalid_argument);
}

// Frames (kept, size 6) observe landmarks (marginalized, size 3): no residual
// touches two landmarks, so H_MM is block-diagonal.
TEST(SchurComplementOfUncoupledBlocks, MatchesTheDenseSchurComplement) {
  std::mt19937 rng(4);
  const int keep = 12;
  const std::vector<int> landmark_dims = {3, 3, 2, 3};
  const int dim = keep + 11;
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(0, dim);
  int offset = keep;
  for (const int landmark_dim : landmark_dims) {
    for (int frame = 0; frame < 2; ++frame) {
      Eigen::MatrixXd rows = Eigen::MatrixXd::Zero(2, dim);
      rows.middleCols(6 * frame, 6) = RandomMatrix(2, 6, &rng);
      rows.middleCols(offset, landmark_dim) = RandomMatrix(2, landmark_dim, &rng);
      J.conservativeResize(J.rows() + 2, Eigen::NoChange);
      J.bottomRows(2) = rows;
    }
    offset += landmark_dim;
  }
  J.conservativeResize(J.rows() + keep, Eigen::NoChange);
  J.bottomRows(keep) << RandomMatrix(keep, keep, &rng), Eigen::MatrixXd::Zero(keep, dim - keep);
  const Eigen::VectorXd r = RandomMatrix(static_cast<int>(J.rows()), 1, &rng);
  const Eigen::MatrixXd H = J.transpose() * J;
  const Eigen::VectorXd b = J.transpose() * r;

  const NormalEquations dense = SchurComplement(H, b, keep, dim - keep);
  const NormalEquations blockwise = SchurComplementOfUncoupledBlocks(H, b, keep, landmark_dims);
  EXPECT_LT(RelativeError(blockwise.H, dense.H), 1e-10);
  EXPECT_LT(RelativeError(blockwise.b, dense.b), 1e-10);
}

TEST(SchurComplementOfUncoupledBlocks, RejectsCoupledBlocks) {
  std::mt19937 rng(5);
  const NormalEquations full = RandomNormalEquations(12, 6, &rng);  // dense: all coupled
  EXPECT_THROW(SchurComplementOfUncoupledBlocks(full.H, full.b, 2, {2, 2}), std::invalid_argument);
  EXPECT_THROW(SchurComplementOfUncoupledBlocks(full.H, full.b, 2, {2, 3}), std::invalid_argument);
}

TEST(PseudoInverse, SatisfiesThePenroseConditionsOnARankDeficientMatrix) {
  std::mt19937 rng(6);
  const Eigen::MatrixXd J = RandomMatrix(3, 6, &rng);  // rank 3 in R^6
  const Eigen::MatrixXd H = J.transpose() * J;
  const Eigen::MatrixXd H_pinv = PseudoInverse(H);
  EXPECT_LT(RelativeError(H * H_pinv * H, H), 1e-10);
  EXPECT_LT(RelativeError(H_pinv * H * H_pinv, H_pinv), 1e-10);
}

// 3x3 blocks (landmarks) take a fixed-size path: the inverse at full rank, the
// Penrose conditions at ranks 2 and 1, and the null directions dropped.
TEST(PseudoInverse, ThreeByThreeBlocksAtEveryRank) {
  std::mt19937 rng(8);
  for (const int rank : {3, 2, 1}) {
    const Eigen::MatrixXd J = RandomMatrix(rank, 3, &rng);
    const Eigen::MatrixXd H = J.transpose() * J;
    const Eigen::MatrixXd H_pinv = PseudoInverse(H);
    ASSERT_EQ(H_pinv.rows(), 3);
    EXPECT_LT(RelativeError(H * H_pinv * H, H), 1e-10) << "rank " << rank;
    EXPECT_LT(RelativeError(H_pinv * H * H_pinv, H_pinv), 1e-10) << "rank " << rank;
    if (rank == 3) {
      EXPECT_LT(RelativeError(H_pinv, H.inverse()), 1e-10);
    }
    const Eigen::FullPivLU<Eigen::MatrixXd> lu(J);
    const Eigen::MatrixXd null_space = lu.kernel();
    if (rank < 3) {
      EXPECT_LT((H_pinv * null_space).norm(), 1e-10 * H_pinv.norm()) << "rank " << rank;
    }
  }
}

class SqrtInformationFromHessianTest : public ::testing::TestWithParam<SqrtMethod> {};

TEST_P(SqrtInformationFromHessianTest, ReproducesFullRankInformationAndVector) {
  std::mt19937 rng(7);
  const NormalEquations eq = RandomNormalEquations(15, 7, &rng);
  const SqrtInformation prior = SqrtInformationFromHessian(eq.H, eq.b, {}, GetParam());
  ASSERT_EQ(prior.sqrt_information.rows(), 7);
  const Eigen::MatrixXd& Jp = prior.sqrt_information;
  EXPECT_LT(RelativeError(Jp.transpose() * Jp, eq.H), 1e-12);
  EXPECT_LT(RelativeError(Jp.transpose() * prior.residual, eq.b), 1e-12);
}

TEST_P(SqrtInformationFromHessianTest, DropsTheNullSpaceOfRankDeficientInformation) {
  std::mt19937 rng(8);
  const Eigen::MatrixXd J = RandomMatrix(2, 5, &rng);  // rank 2
  const Eigen::VectorXd r = RandomMatrix(2, 1, &rng);
  const Eigen::MatrixXd H = J.transpose() * J;
  const Eigen::VectorXd b = J.transpose() * r;  // in the range of H
  const SqrtInformation prior = SqrtInformationFromHessian(H, b, {}, GetParam());
  ASSERT_EQ(prior.sqrt_information.rows(), 2);
  const Eigen::MatrixXd& Jp = prior.sqrt_information;
  EXPECT_LT(RelativeError(Jp.transpose() * Jp, H), 1e-12);
  EXPECT_LT(RelativeError(Jp.transpose() * prior.residual, b), 1e-12);
  // Same cost up to a constant: |r0 + Jp dx|^2 - |r + J dx|^2 does not depend on dx.
  const Eigen::VectorXd dx = RandomMatrix(5, 1, &rng);
  const double difference_at_dx =
      (prior.residual + Jp * dx).squaredNorm() - (r + J * dx).squaredNorm();
  const double difference_at_0 = prior.residual.squaredNorm() - r.squaredNorm();
  EXPECT_NEAR(difference_at_dx, difference_at_0, 1e-10);
}

TEST_P(SqrtInformationFromHessianTest, GaugeFreedomOfAWindowIsDropped) {
  // 40 variables observed only through differences x_i - x_j: the common
  // offset (1, ..., 1) is unobservable, like the position of a VIO window.
  std::mt19937 rng(9);
  std::uniform_int_distribution<int> pick(0, 39);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(120, 40);
  for (int row = 0; row < 120; ++row) {
    const int i = row % 40;
    const int j = (i + 1 + pick(rng) % 39) % 40;
    J(row, i) = 1.0 + 0.1 * (row % 7);
    J(row, j) = -J(row, i);
  }
  const Eigen::VectorXd r = RandomMatrix(120, 1, &rng);
  const Eigen::MatrixXd H = J.transpose() * J;
  const Eigen::VectorXd b = J.transpose() * r;
  const SqrtInformation prior = SqrtInformationFromHessian(H, b, {}, GetParam());
  ASSERT_EQ(prior.sqrt_information.rows(), 39);
  const Eigen::MatrixXd& Jp = prior.sqrt_information;
  EXPECT_LT(RelativeError(Jp.transpose() * Jp, H), 1e-12);
  EXPECT_LT(RelativeError(Jp.transpose() * prior.residual, b), 1e-12);
  EXPECT_LT((Jp * Eigen::VectorXd::Ones(40)).norm(), 1e-10 * Jp.norm());
}

TEST_P(SqrtInformationFromHessianTest, InformationIsJpTransposeJp) {
  std::mt19937 rng(12);
  for (const int rank : {9, 5}) {
    const Eigen::MatrixXd J = RandomMatrix(rank, 9, &rng);
    const SqrtInformation prior =
        SqrtInformationFromHessian(J.transpose() * J, J.transpose() * RandomMatrix(rank, 1, &rng), {}, GetParam());
    const Eigen::MatrixXd& Jp = prior.sqrt_information;
    ASSERT_EQ(prior.information.rows(), 9) << "rank " << rank;
    EXPECT_LT(RelativeError(prior.information, Jp.transpose() * Jp), 1e-12) << "rank " << rank;
  }
}

/// A marginal shaped like a long window's: four groups of 10 variables seen
/// only through differences inside the group (a gauge freedom each), at scales
/// 1e2-1e5, and 20 landmark-like variables tied to differences; plus symmetric
/// noise of 1e-15 |H|, the round-off of forming H from many Schur updates.
/// Rank 56; the noise makes the null directions slightly indefinite.
NormalEquations WindowLikeMarginal(int seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  constexpr int kGroups = 4, kPerGroup = 10, kGrouped = kGroups * kPerGroup, kTied = 20;
  std::uniform_int_distribution<int> member(0, kPerGroup - 1), group(0, kGroups - 1);
  const auto other_member = [&](int g, int i) { return g * kPerGroup + (i - g * kPerGroup + 1 + member(rng) % (kPerGroup - 1)) % kPerGroup; };
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(3 * kGrouped + 2 * kTied, kGrouped + kTied);
  int row = 0;
  for (int g = 0; g < kGroups; ++g) {
    for (int t = 0; t < 3 * kPerGroup; ++t, ++row) {
      const int i = g * kPerGroup + t % kPerGroup;
      const double weight = std::pow(10.0, 2 + g) * (1.0 + 0.1 * normal(rng));
      J(row, i) = weight;
      J(row, other_member(g, i)) = -weight;
    }
  }
  for (int t = 0; t < 2 * kTied; ++t, ++row) {
    const int g = group(rng);
    const int i = g * kPerGroup + member(rng);
    J(row, kGrouped + t % kTied) = 1.0 + 0.1 * normal(rng);
    J(row, i) = -30.0;
    J(row, other_member(g, i)) = 30.0;
  }
  NormalEquations eq{J.transpose() * J, J.transpose() * RandomMatrix(static_cast<int>(J.rows()), 1, &rng)};
  const Eigen::MatrixXd noise = RandomMatrix(static_cast<int>(J.cols()), static_cast<int>(J.cols()), &rng);
  eq.H += 0.5e-15 * eq.H.norm() * (noise + noise.transpose());
  return eq;
}

TEST_P(SqrtInformationFromHessianTest, KeepsTheRankOfAWindowLikeMarginal) {
  // Pivoting on H's own diagonal (Eigen::LDLT) meets a round-off pivot before
  // the large diagonals are used up and divides by it: on these matrices its
  // factor misses H by 1e-13 to 3e-12 (relative) in 16 of 20 seeds.
  for (int seed = 1; seed <= 5; ++seed) {
    const NormalEquations eq = WindowLikeMarginal(seed);
    const SqrtInformation prior = SqrtInformationFromHessian(eq.H, eq.b, {}, GetParam());
    const Eigen::MatrixXd& Jp = prior.sqrt_information;
    ASSERT_EQ(Jp.rows(), 56) << "seed " << seed;
    EXPECT_LT(RelativeError(Jp.transpose() * Jp, eq.H), 1e-13) << "seed " << seed;
    if (GetParam() != SqrtMethod::kEigen) {
      // L^T P, not the eigen fallback: upper trapezoidal up to the column order.
      const Eigen::Index rank = Jp.rows(), n = Jp.cols();
      EXPECT_LE((Jp.array() != 0.0).count(), rank * n - rank * (rank - 1) / 2) << "seed " << seed;
    }
  }
}

// Weak directions just below the rank threshold (eigenvalues 2e-13 and 5e-13
// of the largest, under the 1e-12 cutoff) leave the pivoted factor a
// remainder of that size, more than 1e-13 of H but no more than the dropped
// diagonal allows: the pivoted factor is kept (no eigen fallback), it drops
// those directions as the eigen square root does, and gives H back to what it
// dropped.
TEST(SqrtInformationFromHessian, WeakDirectionsBelowTheThresholdKeepThePivotedFactor) {
  std::mt19937 rng(16);
  const int n = 14;
  const Eigen::MatrixXd Q = RandomMatrix(n, n, &rng).householderQr().householderQ();
  Eigen::VectorXd lambda(n);
  lambda << 1.0, 0.8, 0.5, 0.3, 0.2, 0.1, 0.05, 0.02, 0.01, 5e-13, 5e-13, 2e-13, 0.0, 0.0;
  const Eigen::MatrixXd H = Q * lambda.asDiagonal() * Q.transpose();
  const Eigen::VectorXd b = H * RandomMatrix(n, 1, &rng);
  const SqrtInformation eigen = SqrtInformationFromHessian(H, b, {}, SqrtMethod::kEigen);
  const SqrtInformation pivoted = SqrtInformationFromHessian(H, b, {}, SqrtMethod::kPivotedCholeskyOnly);
  const Eigen::MatrixXd& Jp = pivoted.sqrt_information;
  ASSERT_EQ(eigen.sqrt_information.rows(), 9);
  ASSERT_EQ(Jp.rows(), 9);
  const double error = RelativeError(Jp.transpose() * Jp, H);
  EXPECT_GT(error, 1e-13);  // what made the eigen fallback run before
  EXPECT_LT(error, 2.0 * (n - 9) * 1e-12 * H.diagonal().maxCoeff() / H.norm());
  const Eigen::Index rank = Jp.rows();
  EXPECT_LE((Jp.array() != 0.0).count(), rank * n - rank * (rank - 1) / 2);  // L^T P, not eigenvectors
  EXPECT_NEAR(pivoted.residual.squaredNorm(), eigen.residual.squaredNorm(), 1e-9 * eigen.residual.squaredNorm());
}

TEST(SqrtInformationFromHessian, DefiniteInformationTakesTheCholeskyFactor) {
  std::mt19937 rng(14);
  const Eigen::MatrixXd J = RandomMatrix(30, 12, &rng);
  const Eigen::MatrixXd H = J.transpose() * J;
  const SqrtInformation prior =
      SqrtInformationFromHessian(H, J.transpose() * RandomMatrix(30, 1, &rng), {}, SqrtMethod::kPivotedCholesky);
  const Eigen::MatrixXd& Jp = prior.sqrt_information;
  ASSERT_EQ(Jp.rows(), 12);
  EXPECT_TRUE(Jp.isUpperTriangular(0.0));
  EXPECT_EQ(prior.information, H);  // the factored matrix itself
  EXPECT_LT(RelativeError(Jp.transpose() * Jp, H), 1e-12);
}

// Without the unpivoted attempt a definite H takes the pivoted factor: the
// same information, Jp an orthogonal transform of the Cholesky factor's rows,
// the same r0^T r0 and Jp^T r0 up to round-off.
TEST(SqrtInformationFromHessian, PivotedOnlyGivesTheCholeskyPriorOfADefiniteInformation) {
  std::mt19937 rng(15);
  const Eigen::MatrixXd J = RandomMatrix(40, 18, &rng);
  const Eigen::MatrixXd H = J.transpose() * J;
  const Eigen::VectorXd b = J.transpose() * RandomMatrix(40, 1, &rng);
  const SqrtInformation cholesky = SqrtInformationFromHessian(H, b, {}, SqrtMethod::kPivotedCholesky);
  const SqrtInformation pivoted = SqrtInformationFromHessian(H, b, {}, SqrtMethod::kPivotedCholeskyOnly);
  ASSERT_EQ(pivoted.sqrt_information.rows(), 18);
  EXPECT_FALSE(pivoted.sqrt_information.isUpperTriangular(0.0));  // pivoted: not the plain factor
  EXPECT_EQ(pivoted.information, cholesky.information);  // the factored matrix itself
  EXPECT_LT(RelativeError(pivoted.sqrt_information.transpose() * pivoted.sqrt_information, H), 1e-12);
  EXPECT_NEAR(pivoted.residual.squaredNorm(), cholesky.residual.squaredNorm(), 1e-10 * cholesky.residual.squaredNorm());
  EXPECT_LT(RelativeError(pivoted.sqrt_information.transpose() * pivoted.residual,
                          cholesky.sqrt_information.transpose() * cholesky.residual), 1e-10);
}

TEST_P(SqrtInformationFromHessianTest, ZeroInformationGivesNoRows) {
  const SqrtInformation prior = SqrtInformationFromHessian(
      Eigen::MatrixXd::Zero(4, 4), Eigen::VectorXd::Zero(4), {}, GetParam());
  EXPECT_EQ(prior.sqrt_information.rows(), 0);
  EXPECT_EQ(prior.sqrt_information.cols(), 4);
  EXPECT_EQ(prior.residual.size(), 0);
}

TEST_P(SqrtInformationFromHessianTest, ThresholdsDropSmallEigenvalues) {
  const Eigen::Vector3d lambda(1e6, 1.0, 1e-5);
  const Eigen::MatrixXd H = lambda.asDiagonal();
  const Eigen::VectorXd b = Eigen::Vector3d(1.0, 1.0, 0.0);
  RankThreshold threshold;
  EXPECT_EQ(SqrtInformationFromHessian(H, b, threshold, GetParam()).sqrt_information.rows(),
            3);  // cutoff 1e-6
  threshold.absolute = 1e-4;
  EXPECT_EQ(SqrtInformationFromHessian(H, b, threshold, GetParam()).sqrt_information.rows(), 2);
  threshold.relative = 1e-3;  // cutoff 1e3
  EXPECT_EQ(SqrtInformationFromHessian(H, b, threshold, GetParam()).sqrt_information.rows(), 1);
}

// Marginalizing features seen from few poses leaves a rank-deficient H* with
// round-off where it should be zero; a pivot at that level may come early in
// the pivoted LDLT, and the pivots after it are amplified round-off. The
// square root must still give H* back (as the eigen-decomposition does).
TEST_P(SqrtInformationFromHessianTest, ReconstructsTheRankDeficientMarginalOfFeatures) {
  std::mt19937 engine(7);
  std::normal_distribution<double> normal;
  auto random = [&](int rows, int cols) {
    return Eigen::MatrixXd(Eigen::MatrixXd::NullaryExpr(rows, cols, [&] { return normal(engine); }));
  };
  for (int trial = 0; trial < 20; ++trial) {
    const int poses = 4, features = 3;
    const int n = 6 * poses;
    Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n + 3 * features, n + 3 * features);
    for (int f = 0; f < features; ++f) {
      for (int pose = 0; pose < 2; ++pose) {  // each feature seen from two poses: rank-deficient marginal
        const int i = (f + pose) % poses;
        Eigen::MatrixXd J = Eigen::MatrixXd::Zero(3, n + 3 * features);
        J.middleCols(6 * i, 6) = 100.0 * random(3, 6);
        Eigen::Matrix3d J_f = 100.0 * random(3, 3);
        J_f.col(2) *= 1e-2;  // depth weakly observed
        J.middleCols(n + 3 * f, 3) = J_f;
        H += J.transpose() * J;
      }
    }
    const NormalEquations marginal =
        SchurComplement(H, random(n + 3 * features, 1), n, 3 * features, RankThreshold{});
    const SqrtInformation sqrt = SqrtInformationFromHessian(marginal.H, marginal.b, RankThreshold{}, GetParam());
    const Eigen::MatrixXd back = sqrt.sqrt_information.transpose() * sqrt.sqrt_information;
    EXPECT_LE((back - marginal.H).norm(), 1e-10 * marginal.H.norm()) << "trial " << trial;
  }
}

TEST_P(SqrtInformationFromHessianTest, RejectsNonSquareInput) {
  EXPECT_THROW(SqrtInformationFromHessian(Eigen::MatrixXd::Zero(3, 2), Eigen::VectorXd::Zero(3), {},
                                          GetParam()),
               std::invalid_argument);
}

INSTANTIATE_TEST_SUITE_P(EveryMethod, SqrtInformationFromHessianTest,
                         ::testing::Values(SqrtMethod::kEigen, SqrtMethod::kPivotedCholesky,
                                           SqrtMethod::kPivotedCholeskyOnly),
                         [](const ::testing::TestParamInfo<SqrtMethod>& info) {
                           switch (info.param) {
                             case SqrtMethod::kEigen: return "Eigen";
                             case SqrtMethod::kPivotedCholesky: return "PivotedCholesky";
                             case SqrtMethod::kPivotedCholeskyOnly: return "PivotedCholeskyOnly";
                           }
                           return "unknown";
                         });

}  // namespace
}  // namespace vio::marginalization
