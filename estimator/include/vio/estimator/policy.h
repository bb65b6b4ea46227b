#pragma once
// A policy decides, each frame, which of the three operations on the one cost
// to apply (paper §2.3): which measurements enter the cost, how many
// Gauss-Newton steps to take, and what to marginalize or drop. Policies are
// functions over a Window; they hold no estimation state of their own beyond
// bookkeeping (e.g. which tracks are pending).
#include <chrono>
#include <memory>
#include <vector>

#include "vio/estimator/estimator_options.h"
#include "vio/estimator/window.h"

namespace vio {

/// Wall time of a policy's steps in one frame [ms].
struct PolicyTiming {
  double build_ms = 0;        ///< adding landmarks and observations
  double solve_ms = 0;        ///< Gauss-Newton
  double marginalize_ms = 0;  ///< marginalization and dropping
  int solver_iterations = 0;
};

class Policy {
 public:
  virtual ~Policy() = default;
  /// Called once per frame after `new_state` (linked to the previous state
  /// by its IMU factor) was added to the window.
  virtual PolicyTiming Update(const StereoFrame& frame, StateId new_state, Window& window) = 0;
  /// Called once after the last frame. An offline policy (batch) solves here
  /// and returns true: the window's states are then the run's trajectory.
  virtual bool Finish(Window& /*window*/) { return false; }
  /// States that left the window and that the policy still estimates (the local map's), as last
  /// estimated; they replace those states' estimates as they left.
  virtual std::vector<State> StatesBehindWindow(const Window& /*window*/) const { return {}; }
};

/// The policy named by options.policy.policy. Throws std::invalid_argument
/// for an unknown name.
std::unique_ptr<Policy> MakePolicy(const EstimatorOptions& options);

// ---- building blocks shared by the policies ------------------------------

/// Wall time since `start` [ms].
inline double MillisecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

/// Adds the frame's observations: of landmarks already in the window, and of
/// new landmarks stereo-triangulated from `state`'s current pose (those with
/// too small a disparity or too large a depth are skipped and counted), in
/// the frame's order while the window holds fewer than `max_landmarks` (0: no
/// limit). Returns the number of new landmarks.
int AddStereoObservations(const StereoFrame& frame, StateId state, const ModelOptions& model, Window& window,
                          int max_landmarks = 0);

/// The frame step of the policies that keep every landmark (batch, smoother):
/// the landmarks the frame sees, held constant since, are freed, then its
/// observations are added (AddStereoObservations).
void AddToKeptProblem(const StereoFrame& frame, StateId state, const ModelOptions& model, Window& window);

/// The sliding-window frame step: the frame's observations in (new
/// landmarks stereo-triangulated), IMU factors refreshed, then Gauss-Newton
/// steps; returns the build and solve timings.
PolicyTiming AddFrameAndSolve(const StereoFrame& frame, StateId state, const EstimatorOptions& options,
                              Window& window);

/// The landmarks that leave with the states `leaving` under `swf_landmarks`:
/// those only they see (keep) or every one they see (marginalize).
std::vector<LandmarkId> LandmarksLeavingWith(const std::vector<StateId>& leaving, const PolicyOptions& options,
                                             const Window& window);

/// Marginalizes one state with the landmarks that leave with it (LandmarksLeavingWith).
void MarginalizeStateAndItsLandmarks(StateId state, const PolicyOptions& options, Window& window);

/// Landmarks observed from no state other than those in `leaving`.
std::vector<LandmarkId> LandmarksOnlySeenFrom(const Window& window, const std::vector<StateId>& leaving);

/// Landmarks observed from any of `states`.
std::vector<LandmarkId> LandmarksSeenFrom(const Window& window, const std::vector<StateId>& states);

}  // namespace vio
