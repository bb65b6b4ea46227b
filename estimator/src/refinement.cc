#include "vio/estimator/refinement.h"

#include <algorithm>
#include <chrono>
#include <optional>
#include <utility>

#include <glog/logging.h>

#include "vio/estimator/stereo_geometry.h"
#include "vio/estimator/triangulation.h"
#include "vio/estimator/types.h"

namespace vio {
namespace {

// `to` predicted from `from` through the preintegrated IMU (Forster et al. eq. 33).
void PredictFrom(const State& from, const ImuPreintegration& imu, double gravity, State* to) {
  const ImuPreintegration::Deltas& d = imu.deltas();
  const Eigen::Vector3d g_w(0, 0, -gravity);
  const double dt = NanosToSeconds(to->t_ns - from.t_ns);
  const Eigen::Matrix3d R_w_i = from.q_w_b().toRotationMatrix();
  to->SetPose(from.p_w_b() + from.v_w_b() * dt + 0.5 * g_w * dt * dt + R_w_i * d.delta_p,
              (from.q_w_b() * d.delta_q).normalized());
  to->SetSpeedBias(from.v_w_b() + g_w * dt + R_w_i * d.delta_v, from.gyro_bias(), from.accel_bias());
}

void AddFirstPrior(const MeasurementLog& log, StateId first, Window& whole) {
  if (log.first_prior) {
    whole.AddStatePrior(first, *log.first_prior);
  } else if (log.first_covariance) {
    const Eigen::Matrix<double, 15, 15> information = log.first_covariance->inverse();
    const Eigen::LLT<Eigen::Matrix<double, 15, 15>> llt(0.5 * (information + information.transpose()));
    CHECK(llt.info() == Eigen::Success) << "the logged first covariance is not positive definite";
    whole.AddLinearFactor({first}, {}, llt.matrixU().toDenseMatrix(), Eigen::VectorXd::Zero(15));
  }
}

// The states (at their start values), the first prior and the IMU factors.
void AddStates(const MeasurementLog& log, const StartValue& start, const EstimatorOptions& options, Window& whole) {
  if (log.time_offset) {
    whole.EstimateTimeOffset(log.time_offset->prior_mean_s, log.time_offset->prior_sigma_s);
    whole.SetTimeOffset(log.time_offset->estimate_s);
  }
  const State* previous = nullptr;
  for (const LoggedState& logged : log.states) {
    State& s = whole.AddState(logged.id, logged.t_ns);
    if (!start(logged, &s) && previous != nullptr && logged.imu) {
      PredictFrom(*previous, *logged.imu, options.model.gravity, &s);
    }
    if (previous == nullptr) {
      AddFirstPrior(log, logged.id, whole);
    } else if (logged.imu) {
      whole.AddImuFactor(previous->id, logged.id, *logged.imu);
    }
    if (log.time_offset) whole.SetCameraTiming(logged.id, logged.applied_offset_s, logged.camera_motion);
    previous = &s;
  }
}

Eigen::Isometry3d StartPose(const State& s) { return Eigen::Translation3d(s.p_w_b()) * s.q_w_b(); }

// A landmark never estimated online: triangulated from all its views at the states' start values
// (loose bounds: a start value, not a gate), else stereo-triangulated from the first view that allows it.
std::optional<Eigen::Vector3d> Triangulated(const std::vector<std::pair<StateId, Eigen::Vector3d>>& views,
                                            const ModelOptions& model, const Window& whole) {
  std::vector<StereoView> stereo_views;
  for (const auto& [state, z] : views) stereo_views.push_back({StartPose(whole.state(state)), z});
  TriangulationOptions triangulation;
  triangulation.pixel_sigma = model.pixel_sigma;
  triangulation.max_reprojection_sigma = model.max_whitened_residual;
  triangulation.max_position_sigma_m = model.max_depth_m;
  const TriangulationResult result = TriangulateMultiView(stereo_views, whole.stereo(), triangulation);
  if (result.p_w) return result.p_w;
  for (const auto& [state, z] : views) {
    const std::optional<Eigen::Vector3d> p_cl = TriangulateRectified(z, whole.stereo(), model.min_disparity_px);
    if (p_cl && p_cl->z() <= model.max_depth_m) return StartPose(whole.state(state)) * whole.stereo().T_b_cl * *p_cl;
  }
  return std::nullopt;
}

// Every landmark at its last online estimate or triangulated, with all its observations.
void AddLandmarks(const MeasurementLog& log, const LandmarkStarts& landmarks, const ModelOptions& model,
                  Window& whole, RefinementReport& report) {
  std::map<LandmarkId, std::vector<std::pair<StateId, Eigen::Vector3d>>> views;
  for (const LoggedState& logged : log.states) {
    for (const StereoObservation& obs : logged.observations) views[obs.landmark].emplace_back(logged.id, obs.z_px);
  }
  for (const auto& [id, seen] : views) {
    const auto it = landmarks.find(id);
    std::optional<Eigen::Vector3d> p_w;
    if (it != landmarks.end()) {
      p_w = it->second;
      ++report.started_landmarks;
    } else {
      p_w = Triangulated(seen, model, whole);
      if (p_w) ++report.triangulated_landmarks;
    }
    if (!p_w) continue;
    whole.AddLandmark(id, *p_w);
    for (const auto& [state, z] : seen) whole.AddObservation(state, id, z);
  }
}

}  // namespace

SolveReport SolveWhole(Window& window, const EstimatorOptions& options) {
  SolverOptions solver = options.solver;
  solver.max_iterations = options.batch.batch_final_iterations;
  // Ceres' own tolerance: the default function_tolerance (1e-3) is set for
  // the Gauss-Newton steps of a window, not for the final solve of everything.
  solver.function_tolerance = std::min(1e-6, options.solver.function_tolerance);
  // Bounded by iterations only (a configured wall-time bound is for a window's
  // solves): the final estimate does not depend on machine load.
  solver.max_solver_time_s = 0;
  // The whole system, each segment of states eliminated on its own (Window::EliminationGroups):
  // a whole sequence re-observes landmarks, so eliminating the landmarks first leaves a nearly
  // dense pose system (hybrid V2_01, 40 s: 17.5 s per iteration against 1.0 s).
  solver.linear_solver = "sparse_full";
  return window.SolveSparse(solver);
}

RefinementReport Refine(const MeasurementLog& log, const StartValue& start, const LandmarkStarts& landmarks,
                        const EstimatorOptions& options, Window& whole) {
  const auto begin = std::chrono::steady_clock::now();
  RefinementReport report;
  report.ran = true;
  AddStates(log, start, options, whole);
  AddLandmarks(log, landmarks, options.model, whole, report);
  whole.RefreshImuFactors(options.model.reintegrate_bias_threshold);
  // An observation that does not evaluate at the start values (a landmark at or behind a camera)
  // would fail the whole solve before its first iteration: dropped first, as a window's solve does.
  report.dropped_observations = whole.DropUnevaluableObservations();
  report.states = static_cast<int>(whole.states().size());
  report.landmarks = static_cast<int>(whole.landmarks().size());
  if (report.states > 0) {
    const SolveReport solve = SolveWhole(whole, options);
    report.iterations = solve.iterations;
    report.initial_cost = solve.initial_cost;
    report.final_cost = solve.final_cost;
    report.usable = solve.usable;
    report.stopped = solve.stopped;
    if (whole.estimates_time_offset()) report.time_offset_s = whole.time_offset_s();
  }
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
  LOG(INFO) << "refinement: " << report.states << " states, " << report.landmarks << " landmarks ("
            << report.dropped_observations << " observations dropped), "
            << report.iterations << " iterations, cost " << report.initial_cost << " -> " << report.final_cost
            << ", " << report.seconds << " s";
  return report;
}

}  // namespace vio
