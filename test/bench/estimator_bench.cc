// Micro-benchmarks of the estimator's three operations on a window the size
// SWF(10) keeps: build (IMU preintegration of one frame interval), Gauss-
// Newton (`Window::Solve`, 3 iterations from a perturbed start) and
// marginalization (the oldest state with the landmarks it saw). The data is
// a synthetic flight from the simulator (features at 0.5 px).
//   build/bin/vio_bench [--benchmark_filter=Solve] [--benchmark_repetitions=5]
// Whole-pipeline speed is `vio run` / `vio sweep` (ms per frame); these time
// one step each, in isolation.
#include <memory>

#include <benchmark/benchmark.h>

#include "synthetic_window.h"
#include "vio/estimator/policy.h"
#include "vio/estimator/window.h"

namespace vio {
namespace {

SolverOptions ThreeIterations() {
  SolverOptions solver;
  solver.max_iterations = 3;
  return solver;
}

constexpr int kWindowStates = 10;
constexpr int kFirstFrame = 80;      // into the moving part of the flight
constexpr double kStartOffsetM = 0.02;  // the window starts this far off the ground truth

const test::SyntheticFlight& TheFlight() {
  static const test::SyntheticFlight flight(8.0, 11);
  return flight;
}

// A fresh window of kWindowStates states, 3 Gauss-Newton iterations solved
// when `solved`.
std::unique_ptr<Window> MakeWindow(bool solved) {
  const test::SyntheticFlight& flight = TheFlight();
  auto window = std::make_unique<Window>(ModelOptions{}, flight.stereo());
  flight.Build(*window, ModelOptions{}, kFirstFrame, kWindowStates, kStartOffsetM);
  if (solved) window->Solve(ThreeIterations());
  return window;
}

void BM_PreintegrateOneFrame(benchmark::State& state) {
  const test::SyntheticFlight& flight = TheFlight();
  for (auto _ : state) benchmark::DoNotOptimize(flight.ImuBetween(kFirstFrame));
}
BENCHMARK(BM_PreintegrateOneFrame);

void BM_SolveWindow(benchmark::State& state) {
  for (auto _ : state) {
    state.PauseTiming();
    const std::unique_ptr<Window> window = MakeWindow(/*solved=*/false);
    state.ResumeTiming();
    benchmark::DoNotOptimize(window->Solve(ThreeIterations()));
  }
  state.counters["landmarks"] = static_cast<double>(MakeWindow(false)->landmarks().size());
}
BENCHMARK(BM_SolveWindow)->Unit(benchmark::kMillisecond);

void BM_MarginalizeOldestState(benchmark::State& state) {
  const std::vector<StateId> leaving = {StateId(0)};
  for (auto _ : state) {
    state.PauseTiming();
    const std::unique_ptr<Window> window = MakeWindow(/*solved=*/true);
    const std::vector<LandmarkId> landmarks = LandmarksSeenFrom(*window, leaving);
    state.ResumeTiming();
    window->Marginalize(leaving, landmarks);
  }
}
BENCHMARK(BM_MarginalizeOldestState)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace vio

BENCHMARK_MAIN();
