#pragma once
// The estimator: IMU in, stereo frames in, one pose per frame out. It
// initializes, adds one state per frame (predicted by the IMU and linked by a
// preintegrated IMU factor) and hands the frame to the policy, which works
// on the window.
#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "vio/estimator/dynamic_initializer.h"
#include "vio/estimator/estimator_options.h"
#include "vio/estimator/initializer.h"
#include "vio/estimator/policy.h"
#include "vio/estimator/refinement.h"
#include "vio/estimator/rig_checks.h"
#include "vio/estimator/rig_rotation_search.h"
#include "vio/estimator/time_offset_search.h"
#include "vio/estimator/tracking_monitor.h"
#include "vio/estimator/window.h"
#include "vio/estimator/window_covariance.h"

namespace vio {

/// Wall time of one frame's stages [ms].
struct FrameTiming {
  double propagate_ms = 0;  ///< preintegration and the new state
  PolicyTiming policy;
  double total_ms = 0;
};

/// The estimate after one frame.
struct FrameEstimate {
  Timestamp t_ns = 0;
  bool initialized = false;   ///< false while waiting for initialization
  Eigen::Vector3d p_w_b = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_w_b = Eigen::Quaterniond::Identity();
  Eigen::Vector3d v_w_b = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_bias = Eigen::Vector3d::Zero();
  int num_states = 0;
  int num_landmarks = 0;
  int num_observations = 0;   ///< stereo observations in the frame
  int num_residuals = 0;      ///< residual blocks in the cost after the frame's update
  FrameTiming timing;
};

class Estimator {
 public:
  Estimator(const EstimatorOptions& options, const ImuCalibration& imu, const RectifiedStereo& stereo);

  /// IMU samples must arrive in time order, before the frames they precede.
  void AddImu(const ImuSample& sample);
  /// Starts from a known state at the first frame (--init=groundtruth).
  void SetInitialState(const InitialState& state);
  /// Processes one stereo frame; IMU up to ImuTimeOf(frame.t_ns) must have been added. The frame's
  /// state (and its estimate's t_ns) is at that IMU time.
  FrameEstimate ProcessFrame(const StereoFrame& frame);
  /// The IMU time of an image stamped camera_t_ns: camera_t_ns minus the camera-IMU time offset
  /// (its current estimate, or the prior mean when it is not estimated).
  Timestamp ImuTimeOf(Timestamp camera_t_ns) const { return camera_t_ns - AppliedTimeOffsetNs(); }
  /// The time offset's estimate [s] (the prior mean when not estimated).
  double time_offset_s() const;
  /// Its marginal standard deviation at the current estimate [s]; nothing when not estimated.
  std::optional<double> TimeOffsetSigma() { return window_.TimeOffsetSigma(); }
  /// The extrinsics' correction's marginal covariance (Window::ExtrinsicCovariance).
  std::optional<Eigen::Matrix<double, 6, 6>> ExtrinsicCovariance() { return window_.ExtrinsicCovariance(); }
  /// The coarse time offset search at initialization, once it decided.
  struct TimeOffsetSearchReport {
    double offset_s = 0;  ///< where the gyro follows the camera best [s]
    double sigma_s = 0;   ///< its standard deviation (optimistic: the frame pairs overlap) [s]
    int pairs = 0;        ///< frame pairs compared
    /// It lies beyond the prior: the windows so far were linearized that far off, and a run from the
    /// start with the prior's mean there (time_offset_prior_mean_ms) is recommended.
    bool restart = false;
  };
  const std::optional<TimeOffsetSearchReport>& time_offset_search() const { return time_offset_search_; }
  /// The rig rotation search at initialization (RigRotationSearch), once it decided.
  struct RigRotationSearchReport {
    Eigen::Vector3d rotation_vector = Eigen::Vector3d::Zero();  ///< the rig's turn in the body, Log(Q) [rad]
    double sigma_rad = 0;  ///< its largest standard deviation over directions (optimistic) [rad]
    int pairs = 0;         ///< frame pairs compared
    bool excited = false;  ///< the motion turned about every axis enough to tell (its sigma below 0.5 deg)
    /// It lies beyond the extrinsics' prior: a run from the start with sensor.yaml's cameras turned
    /// by it is recommended.
    bool restart = false;
  };
  const std::optional<RigRotationSearchReport>& rig_rotation_search() const { return rig_rotation_search_; }
  /// Whether a search at initialization (time offset, rig rotation) is still running.
  bool searching() const { return offset_search_.has_value() || rig_search_.has_value(); }
  /// Whether a search asks to start the run again (time offset or rig rotation).
  bool restart_requested() const {
    return (time_offset_search_ && time_offset_search_->restart) || (rig_rotation_search_ && rig_rotation_search_->restart);
  }

  /// Ends the run. For an offline policy (batch) this is where it solves;
  /// it then returns the final estimate of every state (which replaces the
  /// per-frame estimates). Online policies return nothing.
  std::vector<FrameEstimate> Finish();
  /// Every estimated frame's state as last estimated: a state that left the
  /// window as it was when it left, one still in it as it is now. For a
  /// windowed policy, the output of a fixed-lag smoother (the lag is the
  /// window); with the local map, its keyframes' latest estimates and the
  /// other frames moved with them (LocalMap::LastStates). ProcessFrame's
  /// per-frame estimates are the filter's.
  std::vector<FrameEstimate> LastEstimates() const;
  /// Keeps every frame's measurements (observations after gating, IMU factors, the first prior) from
  /// now on, for Refine: call before the first frame.
  void KeepMeasurements() { log_.emplace(); }
  /// The offline refinement (refinement.h): every kept state, landmark and IMU factor solved together,
  /// started from LastEstimates() and each landmark's last online estimate. Nothing when no measurements were kept or the solve was unusable.
  std::vector<FrameEstimate> Refine(RefinementReport* report) const;

  /// The body pose at t_ns predicted by the IMU from the newest state (for a
  /// front end's outlier rejection); nothing before initialization or when
  /// the IMU does not reach t_ns yet.
  std::optional<Eigen::Isometry3d> PredictBodyPose(Timestamp t_ns) const;

  const Window& window() const { return window_; }
  /// The caller's stop request and progress hook for every solve from now on (solve_control.h):
  /// a stopped solve keeps its iterate and counts in window().health().stopped_solves.
  void SetSolveControl(SolveControl control) { window_.SetSolveControl(std::move(control)); }
  /// The newest state's marginal covariance from the window's information
  /// at the current estimate (window_covariance.h); nothing before
  /// initialization or when the information is singular.
  std::optional<StateCovariance> NewestCovariance() { return NewestStateCovariance(window_); }
  /// Frames lost to too few observations (propagated on the IMU).
  const TrackingReport& tracking() const { return tracking_.report(); }
  /// Why initialization has not happened yet (empty once initialized).
  const std::string& waiting_reason() const { return waiting_reason_; }
  /// The initializer's estimates of frames before the first state (time order), once, after the
  /// frame that initialized: static, the frames of the still IMU window (at the first state's pose,
  /// at rest); dynamic, the refinement's estimates of the window's earlier frames. Not re-estimated
  /// by the window (their information is in the first state's prior).
  std::vector<FrameEstimate> TakeEarlierEstimates() { return std::exchange(earlier_estimates_, {}); }
  /// How the run started: static, dynamic or groundtruth (empty before initialization).
  const std::string& init_method() const { return init_method_; }
  /// Observations rejected by the whitened-residual gate (model.max_whitened_residual).
  int rejected_observations() const { return rejected_observations_; }
  /// Set when the rig cannot be right (rig_checks.h: the IMU at rest, the initializers' biases and
  /// gravity, the gyro against the camera's rotation): what is wrong and how to fix it. The run
  /// should stop there; the estimator does not initialize on such a rig.
  const std::string& input_problem() const { return input_problem_; }

 private:
  struct Prediction {
    ImuPreintegration preintegration;
    Eigen::Vector3d p_w_b = Eigen::Vector3d::Zero();
    Eigen::Vector3d v_w_b = Eigen::Vector3d::Zero();
    Eigen::Quaterniond q_w_b = Eigen::Quaterniond::Identity();
  };
  Prediction Predict(Timestamp t_ns) const;
  bool Initialize(const StereoFrame& frame);
  /// Static initialization at the frame; auto: only when the camera agrees that it is still.
  /// `moving`: the IMU (or, auto, the camera) moves.
  std::optional<InitialState> TryStatic(const StereoFrame& frame, std::string* reason, bool* moving);
  /// The dynamic initializer's gravity and biases against the rig's limits; an implausible result
  /// `kImplausibleInits` attempts in a row is an input problem. Empty when plausible.
  std::string CheckDynamicResult(const DynamicInitResult& result);
  /// The gyro's rotation against the camera's from the previous frame to this one (RotationCheck,
  /// and the time offset search while it runs, at `search_t_ns`: the camera stamp less the prior's mean).
  void CheckRotation(const StereoFrame& frame, Timestamp search_t_ns);
  /// With the offset estimated and time_offset_search_ms > 0: the search starts.
  void StartTimeOffsetSearch();
  /// Makes the window estimate the calibration the options ask for (not with the local map).
  void EstimateCalibration();
  /// The search's result: an input problem when it lies at its range's end, a recommended restart
  /// when beyond the prior (TimeOffsetSearchReport).
  void ApplyTimeOffsetSearch(const TimeOffsetSearch::Result& result);
  /// The rig rotation search's result: a recommended restart when beyond the extrinsics' prior.
  void ApplyRigRotationSearch(const RigRotationSearch::Result& result);
  /// Dynamic initialization from the buffered frames ending at this one.
  bool TryDynamic(std::string* reason);
  /// The buffered frames (time order) from t_ns - span_s on.
  std::vector<StereoFrame> InitFrames(Timestamp t_ns, double span_s) const;
  void AddFirstState(const InitialState& initial, const StatePrior& prior);
  /// The first state under a full 15x15 prior over [pose, speed_bias] (dynamic initialization).
  void AddFirstState(const InitialState& initial, const Eigen::Matrix<double, 15, 15>& covariance);
  StatePrior DefaultFirstPrior(const Eigen::Quaterniond& q_w_b) const;
  void AddPropagatedState(Timestamp t_ns);
  StereoFrame GateObservations(const StereoFrame& frame);
  FrameEstimate Estimate(const StereoFrame& frame) const;
  FrameEstimate EstimateOf(const State& state) const;
  static FrameEstimate EstimateOfInitial(const InitialState& state);
  void PruneImu(Timestamp before_ns);
  Timestamp AppliedTimeOffsetNs() const;
  /// The camera's motion at the newest state: its (IMU-predicted) velocity and the bias-corrected
  /// gyro rate at its time (CameraMotionOf, the estimated rig).
  CameraMotion NewestCameraMotion() const;

  EstimatorOptions options_;
  ImuCalibration imu_calibration_;
  Window window_;
  std::unique_ptr<Policy> policy_;
  TrackingMonitor tracking_;
  std::vector<ImuSample> imu_;
  std::optional<InitialState> given_initial_state_;
  StateId last_state_;
  std::int64_t next_state_id_ = 0;
  std::string waiting_reason_;
  int rejected_observations_ = 0;
  std::vector<FrameEstimate> left_window_;  ///< states that left the window, as they left
  bool waiting_while_moving_ = false;  ///< the IMU moved at the last frame before initialization
  std::vector<StereoFrame> init_frames_;  ///< frames before initialization (the last few seconds)
  std::string init_method_;
  std::vector<FrameEstimate> earlier_estimates_;
  RigLimits rig_limits_;                        ///< from the sensor.yaml noise figures (unscaled)
  /// A frame of the rotation check's span, with the gyro's rotation integrated up to it.
  struct RotationCheckFrame {
    StereoFrame frame;
    Eigen::Vector3d gyro_sum;  ///< the gyro integrated from the first frame kept (IntegratedGyro) [rad]
    Timestamp search_t_ns;     ///< its time for the time offset search (CheckRotation)
  };
  RotationCheck rotation_check_;
  std::deque<RotationCheckFrame> rotation_frames_;  ///< the last RotationCheck::kPairSpanS, until it decided
  std::optional<TimeOffsetSearch> offset_search_;  ///< while the coarse time offset search runs
  Timestamp offset_search_start_ns_ = -1;           ///< the first frame the search saw
  std::optional<TimeOffsetSearchReport> time_offset_search_;  ///< its result, once decided
  std::optional<RigRotationSearch> rig_search_;     ///< while the rig rotation search runs
  /// A frame of the rig rotation search's span, with the gyro's rotation composed up to it.
  struct RigSearchFrame {
    StereoFrame frame;
    Eigen::Quaterniond q_gyro;  ///< the gyro's rotation from the first frame kept to this one
  };
  std::deque<RigSearchFrame> rig_frames_;  ///< the last kRigPairSpanS of frames, while the search runs
  Timestamp rig_search_start_ns_ = -1;     ///< the first frame the search saw
  /// Pairs the frame with the oldest of the span for the rig rotation search; decides at its end.
  void AddRigSearchFrame(const StereoFrame& frame);
  std::optional<RigRotationSearchReport> rig_rotation_search_;  ///< its result, once decided
  int implausible_inits_ = 0;                   ///< dynamic initializations in a row that were implausible
  std::string input_problem_;
  std::optional<MeasurementLog> log_;  ///< with KeepMeasurements: every state's measurements
};

}  // namespace vio
