// Micro-benchmark of the chain solver (estimator/chain_solve.h) on a system
// shaped like SWF(k)'s reduced one after the landmarks are eliminated: k dense
// 6-dim pose blocks first, then the chain of k 9-dim speed/bias blocks; speed/
// bias i couples with poses i and i + 1 (IMU factors) and its neighbours in
// the chain, the first one with every pose (the marginalization prior).
//   build/bin/vio_bench --benchmark_filter=ChainSolve
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include <Eigen/Core>

#include "vio/estimator/chain_solve.h"

namespace vio {
namespace {

struct WindowShapedSystem {
  Eigen::MatrixXd H;  ///< upper triangle used
  Eigen::VectorXd b;
  std::vector<ChainBlock> chain;
};

WindowShapedSystem MakeWindowShapedSystem(int k) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  const int n = 15 * k;
  const auto pose = [](int i) { return 6 * i; };
  const auto speed_bias = [k](int i) { return 6 * k + 9 * i; };
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(4 * n, n);
  int row = 0;
  const auto fill = [&](int rows, std::initializer_list<std::pair<int, int>> columns) {
    for (const auto& [first, size] : columns) {
      for (int r = row; r < row + rows; ++r) {
        for (int c = first; c < first + size; ++c) J(r, c) = normal(rng);
      }
    }
    row += rows;
  };
  fill(6 * k, {{0, 6 * k}});  // landmarks' Schur complement: all poses
  fill(9, {{0, 6 * k}, {speed_bias(0), 9}});  // the prior
  for (int i = 0; i + 1 < k; ++i) {
    fill(15, {{pose(i), 6}, {speed_bias(i), 9}, {pose(i + 1), 6}, {speed_bias(i + 1), 9}});
  }
  WindowShapedSystem system;
  system.H = J.topRows(row).transpose() * J.topRows(row) + Eigen::MatrixXd::Identity(n, n);
  system.b = Eigen::VectorXd::NullaryExpr(n, [&]() { return normal(rng); });
  for (int i = 0; i < k; ++i) system.chain.push_back({speed_bias(i), 9});
  return system;
}

void BM_ChainSolve(benchmark::State& state) {
  const WindowShapedSystem system = MakeWindowShapedSystem(static_cast<int>(state.range(0)));
  ChainSolver solver;
  Eigen::VectorXd dx;
  for (auto _ : state) {
    benchmark::DoNotOptimize(solver.Solve(system.H, system.b, system.chain, 1, &dx));
    benchmark::DoNotOptimize(dx.data());
  }
}
BENCHMARK(BM_ChainSolve)->Arg(10)->Arg(30)->Arg(50)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace vio
