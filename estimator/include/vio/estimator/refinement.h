#pragma once
// The offline refinement (--trajectory=smoothed): after the online pass, one
// global solve of every frame — all states, every landmark, every IMU factor
// and the first state's prior — started from each state's last online
// estimate (as it left the window, or the local map's), so that it converges
// in a few iterations. Batch's final solve is the same solve
// (SolveWhole). The estimator logs what the policy was given per frame
// (MeasurementLog): the observations and the IMU factor, not images.
#include <functional>
#include <map>
#include <optional>
#include <vector>

#include "vio/estimator/estimator_options.h"
#include "vio/estimator/window.h"

namespace vio {

/// One state's measurements, as the policy received them.
struct LoggedState {
  StateId id;
  Timestamp t_ns = 0;
  std::vector<StereoObservation> observations;  ///< after gating; empty when tracking was lost
  std::optional<ImuPreintegration> imu;          ///< from the previous logged state (none for the first)
  /// With the time offset estimated: the offset the state's time was made with [s] and the
  /// camera's motion at the state (Window::SetCameraTiming).
  double applied_offset_s = 0;
  CameraMotion camera_motion{};
};

/// The time offset as the online window estimated it: its prior, and its estimate at the end.
struct LoggedTimeOffset {
  double prior_mean_s = 0;
  double prior_sigma_s = 0;
  double estimate_s = 0;
};

/// Every state's measurements and the first state's prior (one of the two forms).
struct MeasurementLog {
  std::optional<StatePrior> first_prior;
  std::optional<Eigen::Matrix<double, 15, 15>> first_covariance;  ///< dynamic initialization
  std::vector<LoggedState> states;  ///< in time order
  std::optional<LoggedTimeOffset> time_offset;  ///< estimated online: estimated again, from its estimate
  /// Each landmark's last online estimate as it left the window (marginalized or dropped) [m] (world).
  std::map<LandmarkId, Eigen::Vector3d> landmarks;
};

/// The cost of one refinement (summary.json, timing.csv).
struct RefinementReport {
  bool ran = false;
  double seconds = 0;  ///< building and solving [s]
  int iterations = 0;
  int states = 0;
  int landmarks = 0;
  int dropped_observations = 0;  ///< observations that did not evaluate at the start values: dropped before the solve
  int started_landmarks = 0;      ///< landmarks started at their last online estimate
  int triangulated_landmarks = 0; ///< landmarks never estimated online: triangulated from all their observations
  double initial_cost = 0;
  double final_cost = 0;
  bool usable = false;
  bool stopped = false;
  std::optional<double> time_offset_s;  ///< the refined camera-IMU time offset, when estimated [s]  ///< the solve control asked to stop: the iterate reached (usable when finite)
};

/// The final solve over every state and landmark of `window` (batch's, and the refinement's):
/// Levenberg-Marquardt on an id-ordered copy, the whole system by sparse Cholesky with each segment of
/// states and the landmarks only it sees eliminated first (Window::SolveSparse, sparse_full),
/// at most batch.batch_final_iterations iterations, function_tolerance 1e-6, no time bound.
SolveReport SolveWhole(Window& window, const EstimatorOptions& options);

/// The start value of a logged state (its pose and speed/bias set on `state`); false: none (the
/// state is then predicted by the IMU from the previous one).
using StartValue = std::function<bool(const LoggedState& logged, State* state)>;

/// Start values of landmarks: each one's last online estimate [m] (world).
using LandmarkStarts = std::map<LandmarkId, Eigen::Vector3d>;

/// Builds the whole problem of `log` in `whole` (an empty window), each state at its start value, each
/// landmark at its start in `landmarks` or else triangulated from all its observations at the states'
/// start values (or, when that fails, stereo-triangulated from the first observation that allows it),
/// and the time offset (when logged) at its online estimate under its prior, and solves it (SolveWhole).
RefinementReport Refine(const MeasurementLog& log, const StartValue& start, const LandmarkStarts& landmarks,
                        const EstimatorOptions& options, Window& whole);

}  // namespace vio
