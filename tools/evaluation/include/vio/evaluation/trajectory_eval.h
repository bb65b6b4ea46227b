#pragma once
// Trajectory error of an estimate against ground truth.
//
//   1. Associate: ground truth interpolated at every estimate stamp (linear in
//      position, slerp in rotation); stamps outside its span are counted.
//   2. Align: the estimate's world frame mapped onto the ground truth's
//      (posyaw = what a VIO can observe, se3, sim3, or none).
//   3. ATE: position and rotation error of every aligned pose.
//      RPE: error of the relative pose over sub-trajectories of a given
//      length travelled along the ground truth.
//
// One call does it all (`EvaluateTrajectory`); the steps are public for tests
// and for callers that want one of them. Poses are GroundTruthState (only
// t_ns, p_w_b and q_w_b are read), as the TUM and ASL readers return them.
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "vio/estimator/types.h"
#include "vio/dataset/euroc_dataset.h"

namespace vio::tools {

/// How the estimate's world frame is aligned to the ground truth's.
enum class Alignment {
  kPosYaw,  ///< translation + rotation about gravity (z): 4 DoF, roll/pitch untouched
  kSe3,     ///< rigid motion: 6 DoF
  kSim3,    ///< rigid motion and scale: 7 DoF
  kNone,    ///< frames compared as given
};

/// "posyaw" | "se3" | "sim3" | "none"; std::invalid_argument naming the allowed values otherwise.
Alignment ParseAlignment(const std::string& name);
/// The name ParseAlignment accepts.
std::string AlignmentName(Alignment alignment);

/// Median ground-truth sample intervals that make a gap (AssociationOptions::max_gap_ns = 0).
constexpr Timestamp kAutoGapPeriods = 10;

/// How estimate stamps are matched to ground truth.
struct AssociationOptions {
  /// Estimate stamps at most this far outside the ground-truth span take its end sample [ns].
  Timestamp tolerance_ns = 1'000'000;
  /// Ground truth is not interpolated across gaps longer than this [ns]; such stamps are skipped.
  /// 0 = kAutoGapPeriods of the ground truth's median sample interval (EuRoC, 200 Hz: 50 ms;
  /// interpolating across much longer gaps gives degrees of error in fast turns).
  Timestamp max_gap_ns = 0;
};

/// Estimate poses paired with ground truth at the same stamps.
struct AssociatedTrajectory {
  std::vector<Timestamp> t_ns;               ///< the estimate stamps kept, increasing
  std::vector<Eigen::Isometry3d> T_w_b_est;  ///< estimate (in the estimate's world)
  std::vector<Eigen::Isometry3d> T_w_b_gt;   ///< ground truth interpolated at t_ns
  int num_skipped = 0;  ///< estimate stamps outside the ground-truth span or in a gap of it
};

/// Pairs every estimate pose with ground truth interpolated at its stamp.
/// std::invalid_argument when the stamps of either input are not strictly increasing.
AssociatedTrajectory Associate(const std::vector<GroundTruthState>& estimate,
                               const std::vector<GroundTruthState>& groundtruth,
                               const AssociationOptions& options = {});

/// The similarity p_gt = scale * R_gt_est * p_est + p_gt_est (R, p from T_gt_est).
struct AlignmentResult {
  Eigen::Isometry3d T_gt_est = Eigen::Isometry3d::Identity();  ///< estimate world in ground-truth world
  double scale = 1.0;                                            ///< 1 unless sim3
};

/// Closed-form least-squares alignment of the estimate positions onto the
/// ground-truth positions. std::invalid_argument when there are too few poses
/// (posyaw 2, se3/sim3 3, none 1) or, for sim3, the estimate does not move.
AlignmentResult Align(const AssociatedTrajectory& trajectory, Alignment alignment);

/// The alignment that puts the first estimate pose on its ground truth along the
/// directions `alignment` frees (the gauge an estimator fixes with a prior on its
/// first state): posyaw = its position and its rotation about z (the twist about z
/// of R_gt R_est^T, so the remaining first-pose rotation error is a pure tilt);
/// se3 and sim3 = its whole pose (scale 1); none = identity. std::invalid_argument
/// when the trajectory is empty.
AlignmentResult AlignAtFirstPose(const AssociatedTrajectory& trajectory, Alignment alignment);

/// The trajectory with its estimate mapped through `alignment`:
/// T_w_b_est <- T_gt_est * (scale * p, R).
AssociatedTrajectory ApplyAlignment(const AssociatedTrajectory& trajectory,
                                    const AlignmentResult& alignment);

/// Absolute trajectory error of an (aligned) trajectory.
struct AteResult {
  double rmse_m = 0.0;        ///< RMS of |p_est - p_gt| [m]
  double mean_m = 0.0;        ///< [m]
  double median_m = 0.0;      ///< [m]
  double max_m = 0.0;         ///< [m]
  double rot_rmse_deg = 0.0;  ///< RMS of angle(R_gt^T R_est) [deg]
  int num_poses = 0;          ///< poses compared
  int num_skipped = 0;        ///< estimate poses without ground truth (not compared)
};

/// std::invalid_argument when the trajectory is empty.
AteResult ComputeAte(const AssociatedTrajectory& aligned);

/// Relative pose error over one sub-trajectory length; NaN errors when num_pairs = 0.
struct RpeResult {
  double length_m = 0.0;       ///< distance travelled along the ground truth [m]
  double trans_pct = 0.0;      ///< mean |t(E)| / length * 100 [%]
  double rot_deg_per_m = 0.0;  ///< mean angle(E) / length [deg/m]
  int num_pairs = 0;           ///< pose pairs (i, j) compared
};

/// For every start i, j is the first pose with ground-truth path length from i
/// >= L; E = (T_gt_i^-1 T_gt_j)^-1 (T_est_i^-1 T_est_j). Lengths longer than the
/// trajectory give num_pairs = 0. std::invalid_argument for a length <= 0.
std::vector<RpeResult> ComputeRpe(const AssociatedTrajectory& aligned,
                                  const std::vector<double>& lengths_m = {1, 2, 5, 10});

/// What EvaluateTrajectory does.
struct EvaluationOptions {
  Alignment alignment = Alignment::kPosYaw;           ///< estimate-to-ground-truth alignment
  std::vector<double> rpe_lengths_m = {1, 2, 5, 10};  ///< RPE sub-trajectory lengths [m]
  AssociationOptions association;                     ///< stamp matching
};

/// The whole evaluation of one estimate.
struct TrajectoryEvaluation {
  Alignment alignment = Alignment::kPosYaw;
  AlignmentResult alignment_result;
  AteResult ate;
  std::vector<RpeResult> rpe;
};

/// Associate, align, ATE and RPE. std::invalid_argument (with the stamp spans)
/// when too few estimate poses fall within the ground truth.
TrajectoryEvaluation EvaluateTrajectory(const std::vector<GroundTruthState>& estimate,
                                        const std::vector<GroundTruthState>& groundtruth,
                                        const EvaluationOptions& options = {});

/// A JSON object (no trailing newline); NaN values are written as null.
std::string ToJson(const TrajectoryEvaluation& evaluation);
/// A human-readable multi-line report.
std::string ToText(const TrajectoryEvaluation& evaluation);

/// Ground truth from: a EuRoC sequence folder or its mav0/ or
/// state_groundtruth_estimate0/ folder (data.csv preferred, else
/// groundtruth_tum.txt), a *.csv ASL file (17 columns), or a TUM text file.
/// std::invalid_argument when nothing is found; DatasetError on bad content.
std::vector<GroundTruthState> ReadGroundTruthPath(const std::string& file_or_dir);

}  // namespace vio::tools
