// Micro-benchmarks of the estimator's three operations on a window the size
// SWF(10) keeps: build (IMU preintegration of one frame interval), Gauss-
// Newton (`Window::Solve`, 3 iterations from a perturbed start) and
// marginalization (the oldest state with the landmarks it saw). The data is
// a synthetic flight from the simulator (features at 0.5 px).
//   build/bin/vio_bench [--benchmark_filter=Solve] [--benchmark_repetitions=5]
// Whole-pipeline speed is `vio run` / `vio sweep` (ms per frame); these time
// one step each, in isolation.
#include <benchmark/benchmark.h>

#include "vio/estimator/imu_preintegration.h"
#include "vio/estimator/policy.h"
#include "vio/estimator/window.h"
#include "vio/frontend/stereo_rectifier.h"
#include "vio/tools/simulator.h"
#include "vio/tools/stereo_frames.h"

namespace vio {
namespace {

constexpr int kWindowStates = 10;
constexpr int kFirstFrame = 80;  // into the moving part of the flight

struct Flight {
  tools::Simulation sim;
  std::vector<StereoFrame> frames;
  RectifiedStereo stereo;
  ModelOptions model;

  Flight() {
    tools::SimulatorOptions options;
    options.duration_s = 8.0;
    options.seed = 11;
    sim = tools::BuildSimulation(options);
    const frontend::StereoRectifier rectifier(sim.dataset.cameras[0], sim.dataset.cameras[1]);
    stereo = rectifier.rectified();
    tools::StereoFramesReport report;
    frames = tools::StereoFramesFromFeatures(sim.dataset.features, sim.dataset.frames[0], rectifier, 2.0, &report);
  }

  const tools::GroundTruthState& GroundTruthAt(Timestamp t_ns) const {
    const auto& gt = sim.dataset.groundtruth;
    auto it = std::lower_bound(gt.begin(), gt.end(), t_ns,
                               [](const tools::GroundTruthState& g, Timestamp t) { return g.t_ns < t; });
    return it == gt.end() ? gt.back() : *it;
  }

  // kWindowStates states linked by IMU factors, 2 cm off the ground truth,
  // with every observation; a prior on the first.
  void Build(Window& window) const {
    for (int k = 0; k < kWindowStates; ++k) {
      const StereoFrame& frame = frames[kFirstFrame + k];
      const tools::GroundTruthState& gt = GroundTruthAt(frame.t_ns);
      State& s = window.AddState(StateId(k), frame.t_ns);
      s.SetPose(gt.p_w_b + Eigen::Vector3d::Constant(0.02 * (k % 2 ? 1 : -1)), gt.q_w_b);
      s.SetSpeedBias(gt.v_w_b, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
      if (k == 0) {
        StatePrior prior;
        prior.pose_covariance = Eigen::Matrix<double, 6, 6>::Identity() * 1e-6;
        prior.speed_bias_sigma.setConstant(0.1);
        window.AddStatePrior(StateId(k), prior);
      } else {
        window.AddImuFactor(StateId(k - 1), StateId(k),
                            PreintegrateBetween(sim.dataset.imu, frames[kFirstFrame + k - 1].t_ns, frame.t_ns,
                                                ImuBias{}, sim.dataset.imu_calibration));
      }
      AddStereoObservations(frame, StateId(k), model, window);
    }
  }
};

const Flight& TheFlight() {
  static const Flight flight;
  return flight;
}

void BM_PreintegrateOneFrame(benchmark::State& state) {
  const Flight& flight = TheFlight();
  const Timestamp from = flight.frames[kFirstFrame].t_ns, to = flight.frames[kFirstFrame + 1].t_ns;
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        PreintegrateBetween(flight.sim.dataset.imu, from, to, ImuBias{}, flight.sim.dataset.imu_calibration));
  }
}
BENCHMARK(BM_PreintegrateOneFrame);

void BM_SolveWindow(benchmark::State& state) {
  const Flight& flight = TheFlight();
  SolverOptions solver;
  solver.max_iterations = 3;
  for (auto _ : state) {
    state.PauseTiming();
    Window window(flight.model, flight.stereo);
    flight.Build(window);
    state.ResumeTiming();
    benchmark::DoNotOptimize(window.Solve(solver));
  }
  Window window(flight.model, flight.stereo);
  flight.Build(window);
  state.counters["landmarks"] = static_cast<double>(window.landmarks().size());
}
BENCHMARK(BM_SolveWindow)->Unit(benchmark::kMillisecond);

void BM_MarginalizeOldestState(benchmark::State& state) {
  const Flight& flight = TheFlight();
  SolverOptions solver;
  solver.max_iterations = 3;
  for (auto _ : state) {
    state.PauseTiming();
    Window window(flight.model, flight.stereo);
    flight.Build(window);
    window.Solve(solver);
    const std::vector<StateId> leaving = {StateId(0)};
    const std::vector<LandmarkId> landmarks = LandmarksSeenFrom(window, leaving);
    state.ResumeTiming();
    window.Marginalize(leaving, landmarks);
  }
}
BENCHMARK(BM_MarginalizeOldestState)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace vio

BENCHMARK_MAIN();
