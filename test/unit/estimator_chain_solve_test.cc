// ChainSolver solves H dx = -b exactly as a dense Cholesky of the whole
// system does, on systems shaped like a window's reduced one: a chain of 9-dim
// blocks coupled within a band, interleaved with and densely (or, as in a
// window, sparsely) coupled to 6-dim blocks, and refuses (returns false) when H is not positive definite.
#include <algorithm>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "vio/estimator/chain_solve.h"

namespace vio {
namespace {

struct System {
  Eigen::MatrixXd H;  ///< full symmetric
  Eigen::VectorXd b;
  std::vector<ChainBlock> chain;
};

/// k pose-like 6-dim blocks first, then k chain blocks of `chain_size` (9:
/// speed/bias); the chain's part of H couples blocks at most `bandwidth`
/// apart; every other entry is dense.
System MakeSystem(int k, int bandwidth, int seed, int chain_size = 9) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  const int n = (6 + chain_size) * k;
  System system;
  for (int i = 0; i < k; ++i) system.chain.push_back({6 * k + chain_size * i, chain_size});
  // H = J^T J + I from a random J, then the chain's out-of-band blocks cleared
  // (which keeps H symmetric; the diagonal shift keeps it positive definite).
  Eigen::MatrixXd J(2 * n, n);
  for (int r = 0; r < J.rows(); ++r) {
    for (int c = 0; c < n; ++c) J(r, c) = normal(rng);
  }
  system.H = J.transpose() * J + n * Eigen::MatrixXd::Identity(n, n);
  for (int i = 0; i < k; ++i) {
    for (int j = 0; j < k; ++j) {
      if (std::abs(i - j) <= bandwidth) continue;
      system.H.block(system.chain[i].offset, system.chain[j].offset, chain_size, chain_size).setZero();
    }
  }
  system.b = Eigen::VectorXd::NullaryExpr(n, [&]() { return normal(rng); });
  return system;
}

Eigen::VectorXd DenseStep(const System& system) { return system.H.llt().solve(-system.b); }

TEST(ChainSolve, EqualsTheDenseCholeskyStepForEveryBandwidth) {
  for (const int bandwidth : {0, 1, 2, 4}) {
    const System system = MakeSystem(12, bandwidth, 3 + bandwidth);
    // Only the upper triangle is read: garbage below must not matter.
    Eigen::MatrixXd upper = system.H;
    upper.triangularView<Eigen::StrictlyLower>().setConstant(1e6);
    Eigen::VectorXd dx;
    ASSERT_TRUE(ChainSolver().Solve(upper, system.b, system.chain, bandwidth, &dx)) << bandwidth;
    const Eigen::VectorXd expected = DenseStep(system);
    EXPECT_LT((dx - expected).norm(), 1e-12 * expected.norm()) << "bandwidth " << bandwidth;
  }
}

// Speed/bias chains take fixed-size 9 x 9 products; any other block size the
// dynamic-size ones, with the same result.
TEST(ChainSolve, EqualsTheDenseCholeskyStepForChainBlocksOfAnotherSize) {
  for (const int chain_size : {4, 12}) {
    const System system = MakeSystem(10, 1, 17 + chain_size, chain_size);
    Eigen::VectorXd dx;
    ASSERT_TRUE(ChainSolver().Solve(system.H, system.b, system.chain, 1, &dx)) << chain_size;
    const Eigen::VectorXd expected = DenseStep(system);
    EXPECT_LT((dx - expected).norm(), 1e-12 * expected.norm()) << "chain blocks of " << chain_size;
  }
}

// Zeroes the coupling a window does not have between the chain and k poses:
// speed/bias block i (i >= 1) keeps only poses i and i + 1 (its IMU factors);
// the first block keeps every pose (a prior).
void KeepOnlyAWindowsCoupling(System* system) {
  const int k = static_cast<int>(system->chain.size());
  for (int i = 1; i < k; ++i) {
    for (int p = 0; p < k; ++p) {
      if (p == i || p == i + 1) continue;
      system->H.block(6 * p, system->chain[i].offset, 6, 9).setZero();
      system->H.block(system->chain[i].offset, 6 * p, 9, 6).setZero();
    }
  }
}

TEST(ChainSolve, EqualsTheDenseStepWithAWindowsSparseCoupling) {
  // A window's coupling between the chain and the rest: speed/bias block i
  // touches poses i and i + 1 (IMU factors), the first one every pose (a
  // prior), and nothing else, so each chain block updates only its rows.
  const int k = 12;
  System system = MakeSystem(k, 1, 21);
  KeepOnlyAWindowsCoupling(&system);
  Eigen::VectorXd dx;
  ASSERT_TRUE(ChainSolver().Solve(system.H, system.b, system.chain, 1, &dx));
  const Eigen::VectorXd expected = DenseStep(system);
  EXPECT_LT((dx - expected).norm(), 1e-12 * expected.norm());
  // Told the columns each block's rows may be non-zero in (as the window's
  // solver is: its poses and its chain neighbours), the solver reads only those.
  for (int i = 0; i < k; ++i) {
    system.chain[i].first_column = i == 0 ? 0 : 6 * i;
    system.chain[i].end_column = system.chain[std::min(i + 1, k - 1)].offset + 9;
  }
  ASSERT_TRUE(ChainSolver().Solve(system.H, system.b, system.chain, 1, &dx));
  EXPECT_LT((dx - expected).norm(), 1e-12 * expected.norm());
}

TEST(ChainSolve, EqualsTheDenseStepForLongChainsOfAnyLength) {
  // Cyclic reduction runs over several levels (every other block, then every
  // other of those, ...): chains of lengths that are not powers of two, each
  // speed/bias block coupled to its two poses and the first one to all of them.
  for (const int k : {2, 3, 5, 17, 37}) {
    System system = MakeSystem(k, 1, 40 + k);
    KeepOnlyAWindowsCoupling(&system);
    Eigen::VectorXd dx;
    ASSERT_TRUE(ChainSolver().Solve(system.H, system.b, system.chain, 1, &dx)) << k;
    const Eigen::VectorXd expected = DenseStep(system);
    EXPECT_LT((dx - expected).norm(), 1e-12 * expected.norm()) << "a chain of " << k;
  }
}

TEST(ChainSolve, AChainAfterOtherColumnsOrAlone) {
  System system = MakeSystem(8, 1, 11);
  Eigen::VectorXd dx;
  ASSERT_TRUE(ChainSolver().Solve(system.H, system.b, system.chain, 1, &dx));
  EXPECT_LT((dx - DenseStep(system)).norm(), 1e-12 * dx.norm());
  // Only chain blocks: the chain's own part, nothing left to solve densely.
  const int offset = system.chain.front().offset;
  System chain_only;
  chain_only.H = system.H.bottomRightCorner(system.H.rows() - offset, system.H.cols() - offset);
  chain_only.b = system.b.tail(system.b.size() - offset);
  for (ChainBlock block : system.chain) chain_only.chain.push_back({block.offset - offset, block.size});
  ASSERT_TRUE(ChainSolver().Solve(chain_only.H, chain_only.b, chain_only.chain, 1, &dx));
  EXPECT_LT((dx - DenseStep(chain_only)).norm(), 1e-12 * dx.norm());
}

TEST(ChainSolve, ABandTooNarrowForTheCouplingGivesADifferentStep) {
  // The bandwidth is a promise about H: told 1 when it is 2, the solve ignores
  // couplings and the step differs. This guards the caller's band computation.
  const System system = MakeSystem(10, 2, 5);
  Eigen::VectorXd dx;
  ASSERT_TRUE(ChainSolver().Solve(system.H, system.b, system.chain, 1, &dx));
  EXPECT_GT((dx - DenseStep(system)).norm(), 1e-6 * dx.norm());
}

TEST(ChainSolve, RefusesAnIndefiniteChainOrRest) {
  System system = MakeSystem(6, 1, 9);
  Eigen::VectorXd dx;
  System bad_chain = system;
  bad_chain.H(bad_chain.chain[2].offset, bad_chain.chain[2].offset) = -1.0;
  EXPECT_FALSE(ChainSolver().Solve(bad_chain.H, bad_chain.b, bad_chain.chain, 1, &dx));
  System bad_rest = system;
  bad_rest.H(0, 0) = -1e6;
  EXPECT_FALSE(ChainSolver().Solve(bad_rest.H, bad_rest.b, bad_rest.chain, 1, &dx));
}

}  // namespace
}  // namespace vio
