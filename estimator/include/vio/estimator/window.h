#pragma once
// The window manager: the ONE place where the cost is assembled. It owns the
// Ceres problem, its parameter blocks (states and landmarks, keyed by typed
// ids) and its residual blocks (IMU factors, stereo observations, priors), and
// offers the paper's three operations on that one cost (ch. 2-3):
//   build     AddState / AddImuFactor / AddLandmark / AddObservation / priors
//   GN steps  Solve
//   marginalize  Marginalize(states, landmarks): Schur complement into one
//             linearized prior (vio_marginalization) on the same problem;
//             Drop*(): remove without keeping their information.
// Policies (policy.h) are functions over a Window.
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <ceres/ceres.h>

#include "vio/estimator/estimator_options.h"
#include "vio/estimator/first_estimates.h"
#include "vio/estimator/frozen_observations.h"
#include "vio/estimator/gauss_newton.h"
#include "vio/estimator/imu_preintegration.h"
#include "vio/estimator/solve_control.h"
#include "vio/estimator/stereo_geometry.h"
#include "vio/estimator/types.h"
#include "vio/marginalization/block_system.h"
#include "vio/marginalization/marginalizer.h"

namespace vio {

struct KeyedResiduals;
struct IdOrderedCopy;

/// One estimator state: a frame's pose and speed/bias, as parameter blocks.
struct State {
  StateId id;
  Timestamp t_ns = 0;
  double pose[7] = {0, 0, 0, 0, 0, 0, 1};  ///< [p_w_b, q_w_b (x y z w)]
  double speed_bias[9] = {};               ///< [v_w_b, b_g, b_a]

  Eigen::Vector3d p_w_b() const { return Eigen::Vector3d(pose[0], pose[1], pose[2]); }
  Eigen::Quaterniond q_w_b() const { return Eigen::Quaterniond(pose[6], pose[3], pose[4], pose[5]); }
  Eigen::Vector3d v_w_b() const { return Eigen::Vector3d(speed_bias[0], speed_bias[1], speed_bias[2]); }
  Eigen::Vector3d gyro_bias() const { return Eigen::Vector3d(speed_bias[3], speed_bias[4], speed_bias[5]); }
  Eigen::Vector3d accel_bias() const { return Eigen::Vector3d(speed_bias[6], speed_bias[7], speed_bias[8]); }
  void SetPose(const Eigen::Vector3d& p_w_b, const Eigen::Quaterniond& q_w_b);
  void SetSpeedBias(const Eigen::Vector3d& v_w_b, const Eigen::Vector3d& b_g, const Eigen::Vector3d& b_a);
};

/// One landmark: a world point and the states that observe it in the window.
struct Landmark {
  LandmarkId id;
  double p_w[3] = {};               ///< [m]
  std::set<StateId> observed_from;  ///< states with an observation residual
  std::set<StateId> anchored_to;    ///< states with an anchored-point residual (SetAnchoredPoint)

  Eigen::Vector3d position() const { return Eigen::Vector3d(p_w[0], p_w[1], p_w[2]); }
};

/// A Gaussian prior on one state (first-state initialization).
struct StatePrior {
  Eigen::Matrix<double, 6, 6> pose_covariance;    ///< over the pose tangent [dp (m, world), dtheta (rad, body)]
  Eigen::Matrix<double, 9, 1> speed_bias_sigma;   ///< [v (m/s), b_g (rad/s), b_a (m/s^2)]
};

/// What one Solve or TakeSteps did.
struct SolveReport {
  int iterations = 0;
  double initial_cost = 0;
  double final_cost = 0;
  bool usable = true;
  bool converged = false;  ///< gn, Solve: stopped by the convergence criterion, not the cap
  bool stopped = false;    ///< ended early by SolveControl::stop (the iterate reached is kept)
};

/// What Marginalize and the Drop* calls removed, in call order.
struct Removals {
  std::vector<StateId> marginalized_states;
  std::vector<LandmarkId> marginalized_landmarks;
  std::vector<StateId> dropped_states;
  std::vector<LandmarkId> dropped_landmarks;  ///< incl. those a dropped state left unobserved
  std::vector<State> leaving_states;  ///< the marginalized and dropped states, as last estimated
  /// The marginalized and dropped landmarks' positions as last estimated [m] (world).
  std::vector<std::pair<LandmarkId, Eigen::Vector3d>> leaving_landmarks;

  /// Empties every list, keeping their memory for the next frame's.
  void Clear() {
    marginalized_states.clear();
    marginalized_landmarks.clear();
    dropped_states.clear();
    dropped_landmarks.clear();
    leaving_states.clear();
    leaving_landmarks.clear();
  }
};

/// What went wrong in the window and was survived, counted over its life.
struct WindowHealth {
  int dropped_residuals = 0;  ///< residuals that did not evaluate (or not finitely) when marginalized: dropped
  int failed_solves = 0;      ///< solves whose result Ceres reported unusable
  int rejected_steps = 0;     ///< Gauss-Newton steps undone: their end point did not evaluate
  int dropped_observations = 0;  ///< observations that did not evaluate at a rejected step's end point: dropped
  int stopped_solves = 0;     ///< solves ended early by SolveControl::stop (their iterate is not converged)
};

/// How the window's Ceres problem finds the residuals of a parameter block. kPerBlock: every
/// block keeps the set of its residuals (Ceres' enable_fast_removal), so removing a state or
/// landmark costs what it touches; about 130 B per observation. kNone: no sets; a removal scans
/// every residual: for windows that keep everything and remove little (batch, the refinement), or hold
/// few residuals (the MSCKF without a local map: one frame's tracks).
enum class ResidualIndex { kPerBlock, kNone };

class Window {
 public:
  Window(const ModelOptions& model, const RectifiedStereo& stereo, ResidualIndex index = ResidualIndex::kPerBlock);
  ~Window();
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;

  // ---- build the cost -------------------------------------------------------
  State& AddState(StateId id, Timestamp t_ns);
  /// Links two states by an IMU factor over the preintegrated interval.
  void AddImuFactor(StateId from, StateId to, ImuPreintegration preintegration);
  /// Prior on one state at its current value (first state).
  void AddStatePrior(StateId id, const StatePrior& prior);
  Landmark& AddLandmark(LandmarkId id, const Eigen::Vector3d& p_w);
  /// Stereo observation z = (u_L, u_R, v) [px] of `landmark` from `state`; with a calibration block
  /// estimated, a StereoCalibrationFactor on it (the time offset's with the camera motion
  /// SetCameraTiming gave; at rest if none).
  void AddObservation(StateId state, LandmarkId landmark, const Eigen::Vector3d& z_px);

  // ---- calibration: the camera-IMU time offset -------------------------------
  /// Makes the time offset t_d [s] (an image stamped t was taken at IMU time t - t_d) a parameter
  /// block of the window, under the prior N(mean_s, sigma_s^2), starting at the mean; every
  /// observation added from now on depends on it (stereo_calibration_factor.h). Once, before
  /// the first observation.
  void EstimateTimeOffset(double mean_s, double sigma_s);
  bool estimates_time_offset() const { return time_offset_prior_.residual != nullptr; }
  /// Sets the estimate [s] (a start value: the offline refinement's); only when estimated.
  void SetTimeOffset(double s);
  /// Holds the estimated time offset constant in the solves (or frees it again).
  void SetTimeOffsetConstant(bool constant);
  /// The estimate [s] (the prior mean before any observation; 0 when not estimated).
  double time_offset_s() const { return time_offset_[0]; }
  /// Its marginal standard deviation at the current estimate [s]; nothing when not estimated, held
  /// constant, the information is singular, or more than 500 states are variable (a dense inverse).
  std::optional<double> TimeOffsetSigma();
  /// Holds every estimated calibration block (time offset, extrinsics) constant (or frees them).
  void SetCalibrationConstant(bool constant);

  // ---- calibration: the camera-IMU extrinsics --------------------------------
  /// Makes a correction c = (dtheta [rad], dp [m]) of the rig's T_b_cl (R_b_c Exp(dtheta), p_b_c + dp,
  /// the baseline kept; stereo_extrinsic_factor.h) a parameter block of the window under the prior
  /// N(0, diag(sigma_rad^2 I3, sigma_m^2 I3)), starting at 0; every observation added from now on
  /// depends on it. Once, before the first observation.
  void EstimateExtrinsics(double sigma_rad, double sigma_m);
  bool estimates_extrinsics() const { return extrinsic_prior_.residual != nullptr; }
  /// The correction c (zero when not estimated).
  Eigen::Matrix<double, 6, 1> extrinsic_correction() const { return Eigen::Map<const Eigen::Matrix<double, 6, 1>>(extrinsic_); }
  /// Its marginal covariance at the current estimate (as TimeOffsetSigma; nothing when not estimated).
  std::optional<Eigen::Matrix<double, 6, 6>> ExtrinsicCovariance();
  /// The rig with the estimated correction applied (the given rig when not estimated): what
  /// triangulation and gating use.
  RectifiedStereo estimated_stereo() const;
  /// The offset t_a [s] the state's time was made with (its camera stamp minus t_ns) and the
  /// camera's motion at the state: what its observations' factors use (stereo_calibration_factor.h).
  void SetCameraTiming(StateId state, double applied_offset_s, const CameraMotion& motion);
  /// The landmark measured in `anchor`'s body frame (AnchoredPointFactor, no loss): the local
  /// map's summary of the observations of frames it dropped. Replaces the pair's earlier one.
  void SetAnchoredPoint(StateId anchor, LandmarkId landmark, const Eigen::Vector3d& p_b_hat,
                        const Eigen::Matrix3d& sqrt_information);
  /// A linear factor r = residual + jacobian [x ⊟ x0], x0 the current values, over the states'
  /// [pose, speed_bias] and the landmarks in that order; kept as a prior. A Gaussian N(x0, Σ) is
  /// jacobian = Σ^-1/2, residual = 0. Throws std::invalid_argument on inconsistent sizes.
  void AddLinearFactor(const std::vector<StateId>& states, const std::vector<LandmarkId>& landmarks,
                       const Eigen::MatrixXd& jacobian, const Eigen::VectorXd& residual);
  /// Wraps every factor the window creates from now on (a test's factor with a wrong Jacobian);
  /// the wrapper takes ownership of the factor it is given. Empty: none.
  using FactorWrapper = std::function<ceres::CostFunction*(ceres::CostFunction*)>;
  void SetFactorWrapper(FactorWrapper wrapper) { wrapper_ = std::move(wrapper); }

  // ---- Gauss-Newton ---------------------------------------------------------
  /// Steps to convergence. step=gn: undamped Gauss-Newton steps until the
  /// relative cost change is <= function_tolerance or |dx| <= parameter_tolerance
  /// * (|x| + parameter_tolerance), at most max_iterations; step=lm: Ceres'
  /// Levenberg-Marquardt with the same bounds.
  SolveReport Solve(const SolverOptions& options);
  /// Exactly `steps` steps (a filter's update: one Gauss-Newton step); with
  /// step=lm, `steps` Levenberg-Marquardt iterations (rejected ones count).
  SolveReport TakeSteps(int steps, const SolverOptions& options);
  /// The caller's stop request and progress hook, used by every Solve and TakeSteps from now on.
  void SetSolveControl(SolveControl control) { solve_control_ = std::move(control); }
  const SolveControl& solve_control() const { return solve_control_; }
  /// Levenberg-Marquardt over the variable blocks (the constant ones held) on a copy of their cost laid
  /// out by id. options.linear_solver: dense, sparse, iterative: the landmarks not tied by a prior
  /// eliminated first (DENSE_SCHUR, SPARSE_SCHUR, ITERATIVE_SCHUR); sparse_full: the whole system by
  /// sparse Cholesky, segments of states and the landmarks only they see first (EliminationGroups).
  /// Depends only on the values, not on the heap layout (batch's solves; window_sparse_solve.cc).
  SolveReport SolveSparse(const SolverOptions& options);
  /// Drops every observation that does not evaluate (finitely) at the current values, and a landmark
  /// left unobserved that no prior holds (as a rejected step does): the number of observations dropped.
  int DropUnevaluableObservations();
  /// SolveSparse with the observations from constant states replaced by their summaries in
  /// `frozen` (frozen_observations.h): batch's periodic solves. Every constant state's
  /// observations must be in `frozen`.
  SolveReport SolveSparse(const SolverOptions& options, const FrozenObservations& frozen);
  /// Adds the observations of `state` at the current values to `frozen`, before the state is
  /// held constant; the landmarks they see must be variable. `taken`: each part added, appended.
  void SummarizeObservationsOf(StateId state, FrozenObservations& frozen,
                               std::vector<SummarizedObservation>* taken = nullptr) const;
  /// The Gauss-Newton step of one state's [pose, speed_bias] alone, every other block held, over
  /// the residuals on it (priors, IMU factors, observations) at the current values, on its
  /// tangent [dp (m), dtheta (rad), dv, dbg, dba]; zero when they do not evaluate (the smoother's
  /// relinearization test of a held state).
  Eigen::Matrix<double, 15, 1> StateStep(StateId state);
  /// Re-preintegrates IMU factors whose gyro-bias linearization moved too far; only those into
  /// `first_to` and later states (batch: the others start at states frozen since they were checked).
  int RefreshImuFactors(double gyro_bias_threshold,
                        StateId first_to = StateId(std::numeric_limits<std::int64_t>::min()));
  /// J^T J of the whole cost at the current values over the tangent spaces of the states'
  /// [pose, speed_bias] and the landmarks, in that order, every other block held: the information
  /// of one Gauss-Newton step (after Marginalize: of the priors); its inverse is the covariance.
  Eigen::MatrixXd Information(const std::vector<StateId>& states, const std::vector<LandmarkId>& landmarks);

  /// Holds a state's or landmark's blocks fixed in Solve (or frees them).
  void SetStateConstant(StateId id, bool constant);
  void SetLandmarkConstant(LandmarkId id, bool constant);
  bool IsStateConstant(StateId id) const;

  // ---- marginalize or drop ---------------------------------------------------
  /// Marginalizes the states and landmarks (with every residual touching them)
  /// into one linearized prior on what they were connected to.
  void Marginalize(const std::vector<StateId>& states, const std::vector<LandmarkId>& landmarks);
  /// Removes without keeping information.
  void DropObservation(StateId state, LandmarkId landmark);
  void DropLandmark(LandmarkId landmark);
  /// Removes a state between two others without keeping its information:
  /// its observations go (and landmarks left unobserved), its two IMU
  /// factors become one over both intervals. It must not be in a prior.
  void DropState(StateId id);
  /// True when a marginalization prior involves the state.
  bool IsInPrior(StateId id) const;
  /// Removes a state with every factor on it (observations, IMU factors,
  /// priors on it alone) without keeping information and without merging IMU
  /// factors: a keyframe the local map parks outside the cost. Landmarks it
  /// leaves unobserved stay. It must not share a prior with another block.
  void RemoveState(StateId id);
  /// What was removed since the last ClearRemovals (the estimator clears it
  /// every frame; the structural policy tests read it).
  const Removals& removals() const { return removals_; }
  void ClearRemovals() { removals_.Clear(); }

  // ---- queries ---------------------------------------------------------------
  const std::map<StateId, State>& states() const { return states_; }
  const std::map<LandmarkId, Landmark>& landmarks() const { return landmarks_; }
  State& state(StateId id);
  const State& state(StateId id) const;
  bool HasState(StateId id) const { return states_.count(id) > 0; }
  bool HasLandmark(LandmarkId id) const { return landmarks_.count(id) > 0; }
  const Landmark& landmark(LandmarkId id) const;
  /// The state's observations: landmark and z = (u_L, u_R, v) [px], by landmark id.
  std::vector<std::pair<LandmarkId, Eigen::Vector3d>> ObservationsOf(StateId state) const;
  /// The IMU factor into state `to`: its first state and preintegration; null without one.
  const ImuPreintegration* ImuFactorInto(StateId to, StateId* from) const;
  /// Whitened stereo reprojection error of one observation [sigma].
  double ObservationError(StateId state, LandmarkId landmark) const;
  /// Whitened stereo reprojection error of a measurement z = (u_L, u_R, v) of
  /// `landmark` from `state` at the current estimate [sigma]; +inf when the
  /// landmark is (nearly) at or behind the camera.
  double WhitenedError(StateId state, LandmarkId landmark, const Eigen::Vector3d& z_px) const;
  const RectifiedStereo& stereo() const { return *stereo_; }
  int num_priors() const { return static_cast<int>(priors_.size()); }
  const WindowHealth& health() const { return health_; }
  ceres::Problem& problem() { return *problem_; }
  int num_residual_blocks() const { return problem_->NumResidualBlocks(); }
  /// The Gauss-Newton column layout: variable blocks in id order, states
  /// then landmarks tied by a prior (dense); the other landmarks eliminated.
  GaussNewtonLayout Layout() const;

 private:
  struct ImuEdge {
    StateId from;
    StateId to;
    ImuPreintegration preintegration;
    ceres::ResidualBlockId residual = nullptr;
  };
  struct Observation {
    Eigen::Vector3d z_px;
    ceres::ResidualBlockId residual = nullptr;
  };
  struct Prior {
    ceres::ResidualBlockId residual = nullptr;
    std::vector<BlockKey> keys;  ///< of its parameter blocks, in its parameter order
  };
  using ObservationKey = std::pair<StateId, LandmarkId>;
  /// A state's camera timing (SetCameraTiming).
  struct CameraTiming {
    double applied_offset_s = 0;
    CameraMotion motion;
  };
  /// States and landmarks leaving the window (marginalized or dropped), or a solve's variables
  /// with the calibration blocks solved with them (SolvedOf).
  struct Leaving {
    std::set<StateId> states;
    std::set<LandmarkId> landmarks;
    std::set<BlockKey> calibration;
    /// Whether the block is one of theirs.
    bool Has(const BlockKey& key) const;
  };

  void AddImuResidual(ImuEdge& edge);
  /// The stereo factor of one observation: StereoFactor, or with calibration blocks estimated a
  /// StereoCalibrationFactor on them, with the state's camera timing (window_calibration.cc).
  ceres::CostFunction* StereoFactorOf(StateId state, LandmarkId landmark, const Eigen::Vector3d& z_px) const;
  ceres::CostFunction* Wrap(ceres::CostFunction* factor) const { return wrapper_ ? wrapper_(factor) : factor; }
  /// The keys of the blocks of states ([pose, speed_bias] each), then landmarks.
  static std::vector<BlockKey> KeysOf(const std::vector<StateId>& states, const std::vector<LandmarkId>& landmarks);
  /// The blocks of KeysOf(states, landmarks).
  std::vector<double*> Blocks(const std::vector<StateId>& states, const std::vector<LandmarkId>& landmarks);
  /// The parameter block of a state, landmark or estimated calibration block of the window.
  double* BlockOf(const BlockKey& key) const;
  SolveReport GaussNewton(int max_steps, bool until_converged, const SolverOptions& options);
  SolveReport LevenbergMarquardt(const ceres::Solver::Options& base, const SolverOptions& options);
  /// Factors of the copy beyond the window's residuals, each on one landmark block (the caller owns them).
  using LandmarkFactors = std::vector<std::pair<LandmarkId, ceres::CostFunction*>>;
  struct VariableIds {
    std::vector<StateId> states;
    std::vector<LandmarkId> landmarks;
  };
  VariableIds VariableIdsOf() const;
  /// The variable blocks' Leaving, with the calibration blocks that are estimated and variable.
  Leaving SolvedOf(const VariableIds& variable);
  IdOrderedCopy CopyOf(const KeyedResiduals& residuals, const LandmarkFactors& extra) const;
  /// The elimination group of each block (states, landmarks, calibration), by its key.
  std::vector<int> EliminationGroups(const std::string& linear_solver, const std::vector<BlockKey>& blocks) const;
  /// Levenberg-Marquardt on the copy of `residuals` and `extra` (`residuals` freed before it starts).
  SolveReport SolveCopy(const SolverOptions& options, KeyedResiduals residuals, const LandmarkFactors& extra);
  /// The residuals SolveSparse(options, frozen) copies: those of the variable states (priors, IMU
  /// factors, observations, anchored points) and the priors on the variable landmarks, in ResidualOrder().
  KeyedResiduals RecentResidualOrderOf(const Leaving& solved) const;
  /// The landmarks some prior holds.
  std::set<LandmarkId> LandmarksInPriors() const;
  /// Every residual block: priors in creation order, IMU factors and
  /// observations by ids (never by address).
  std::vector<ceres::ResidualBlockId> ResidualOrder() const;
  Leaving LeavingOf(const std::vector<StateId>& states, const std::vector<LandmarkId>& landmarks);
  /// The observations and anchored points of what leaves, found once for a marginalization's
  /// residual order and its bookkeeping.
  struct LeavingKeys {
    std::set<ObservationKey> observations;
    std::set<ObservationKey> anchored;
  };
  LeavingKeys LeavingKeysOf(const Leaving& leaving) const;
  /// ResidualOrder() restricted to the residuals of what leaves (`keys`: LeavingKeysOf(leaving)), with
  /// their blocks' keys.
  KeyedResiduals ResidualOrderOf(const Leaving& leaving, const LeavingKeys& keys) const;
  /// Appends the anchored points `keys` to `order`.
  void AddAnchoredPoints(const std::set<ObservationKey>& keys, KeyedResiduals* order) const;
  /// The blocks the residuals of what leaves touch that stay (its Markov blanket), in the
  /// marginalization's column order (MarginalizationOptions::kept_order): speed/bias blocks, then
  /// poses (by state id), the time offset, then the others in order of first appearance.
  std::vector<BlockKey> KeptOrderOf(const KeyedResiduals& residuals, const Leaving& leaving) const;
  /// The options of a marginalization of what leaves over `residuals` (kept order, first estimates).
  marginalization::MarginalizationOptions MarginalizationOptionsOf(const KeyedResiduals& residuals,
                                                                   const Leaving& leaving,
                                                                   std::vector<BlockKey>* kept_order);
  /// Keeps a marginalization's prior: its keys (a subsequence of `kept_order`), its first estimates.
  void KeepPrior(ceres::ResidualBlockId prior, const std::vector<BlockKey>& kept_order);
  /// The observations of what leaves, in the map's order.
  std::set<ObservationKey> ObservationKeysOf(const Leaving& leaving) const;
  bool Touches(const Prior& prior, const Leaving& leaving) const;
  bool Touches(StateId to, const ImuEdge& edge, const Leaving& leaving) const;
  std::shared_ptr<ceres::ParameterBlockOrdering> SchurOrdering() const;
  std::shared_ptr<ceres::ParameterBlockOrdering> StatesFirstOrdering() const;
  void ChooseLinearSolver(const std::string& linear_solver, ceres::Solver::Options* solver) const;
  void ForgetResidualsOf(const Leaving& leaving);
  void ForgetResidualsOf(const Leaving& leaving, const LeavingKeys& keys);
  /// Removes the residuals that do not evaluate (finitely) at the current values from the problem and the list.
  void DropUnevaluableResiduals(KeyedResiduals* residuals);
  /// MarginalizeBlocks of what leaves over `residuals`, after DropUnevaluableResiduals only when it
  /// fails: the prior, or null; `kept_order`: its kept blocks' order (KeptOrderOf).
  ceres::ResidualBlockId MarginalizeEvaluable(const std::vector<double*>& blocks, KeyedResiduals residuals,
                                              const Leaving& leaving, std::vector<BlockKey>* kept_order);
  /// The observations whose residual does not evaluate (finitely) at the current values, by ids.
  std::vector<ObservationKey> UnevaluableObservations() const;
  /// Drops `observations`, and a landmark left unobserved that no prior holds.
  void DropOutlierObservations(const std::vector<ObservationKey>& observations);
  void RemoveStateBookkeeping(StateId id);
  void RemoveLandmarkBookkeeping(LandmarkId id);
  /// The keys of `residuals` (observations_ or anchored_points_) on what leaves; `by`: the
  /// landmark's states with such a residual.
  template <typename Residuals>
  std::set<ObservationKey> KeysOf(const Residuals& residuals, std::set<StateId> Landmark::*by,
                                  const Leaving& leaving) const;
  /// The anchored points of the states and landmarks that leave, by ids.
  std::set<ObservationKey> AnchoredKeysOf(const Leaving& leaving) const;
  /// Unobserved and unanchored: a landmark no residual but a prior's holds.
  static bool Unconstrained(const Landmark& landmark) {
    return landmark.observed_from.empty() && landmark.anchored_to.empty();
  }
  /// FEJ (model.fej): `factor` wrapped to take its Jacobians on held blocks at
  /// their first estimates; `factor` itself without FEJ.
  ceres::CostFunction* WithFirstEstimates(ceres::CostFunction* factor, std::vector<BlockKey> keys) const;
  /// FEJ: holds the blocks of a new prior at their current values (blocks with
  /// a first estimate keep it).
  void HoldFirstEstimates(const std::vector<BlockKey>& keys);

  ModelOptions model_;
  /// The given rig, one object that every stereo factor of the window shares (immutable: the
  /// estimated correction is a parameter block).
  std::shared_ptr<const RectifiedStereo> stereo_;
  std::unique_ptr<ceres::Manifold> pose_manifold_;
  std::unique_ptr<ceres::LossFunction> loss_;
  std::unique_ptr<ceres::Problem> problem_;
  std::map<StateId, State> states_;
  std::map<LandmarkId, Landmark> landmarks_;
  /// The states and landmarks not held constant (Set*Constant), kept as they change: a solve's
  /// variables without a walk over everything the window keeps.
  std::set<StateId> variable_states_;
  std::set<LandmarkId> variable_landmarks_;
  std::map<StateId, ImuEdge> imu_edges_;  ///< keyed by the later state (`to`)
  std::map<ObservationKey, Observation> observations_;
  std::map<ObservationKey, ceres::ResidualBlockId> anchored_points_;
  std::vector<Prior> priors_;
  double time_offset_[1] = {0.0};  ///< [s]; a parameter block once EstimateTimeOffset was called
  Prior time_offset_prior_;        ///< also in priors_; null residual: not estimated
  std::map<StateId, CameraTiming> camera_timing_;
  double extrinsic_[6] = {};       ///< c = (dtheta, dp); a parameter block once EstimateExtrinsics was called
  Prior extrinsic_prior_;          ///< also in priors_; null residual: not estimated
  /// The estimated calibration blocks (time offset, then extrinsics), in that order, with their keys.
  std::vector<std::pair<double*, BlockKey>> KeyedCalibrationBlocks() const;
  /// KeyedCalibrationBlocks()' blocks alone.
  std::vector<double*> CalibrationBlocks() const;
  /// KeyedCalibrationBlocks()' keys alone.
  std::vector<BlockKey> CalibrationKeys() const;
  /// The marginal covariance of `block` (a calibration block), as TimeOffsetSigma.
  std::optional<Eigen::MatrixXd> CalibrationCovariance(const double* block);
  /// Whether the last marginalization's prior had fewer rows than columns
  /// (Marginalize picks the next square root's factorization by it).
  bool last_prior_rank_deficient_ = false;
  std::shared_ptr<FirstEstimates> first_estimates_;  ///< model.fej: the held blocks; else null
  Removals removals_;
  WindowHealth health_;
  FactorWrapper wrapper_;
  SolveControl solve_control_;
  /// The exact Gauss-Newton path's solver, re-laid out for every solve: its
  /// buffers (a window's normal equations, a few MB) are reused frame after frame.
  std::unique_ptr<GaussNewtonSolver> gauss_newton_;
  /// The marginalizations' assembly, kept likewise (MarginalizationOptions::system).
  std::unique_ptr<marginalization::BlockSystem> marginal_system_;
};

}  // namespace vio
