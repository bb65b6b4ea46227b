#pragma once
// The files of one run's output folder (see run.h). Private to tools.
// trajectory.txt grows a line (flushed) per AddFrame, so that a run stopped
// at any point leaves the frames estimated so far; WriteTrajectory then
// replaces it whole (temporary file + rename) with the run's final poses.
#include <fstream>
#include <string>
#include <vector>

#include "vio/estimator/estimator.h"
#include "vio/dataset/euroc_dataset.h"
#include "vio/cli/run.h"

namespace vio::tools {

class RunOutput {
 public:
  /// Creates `dir`; throws std::runtime_error when it cannot.
  explicit RunOutput(std::string dir);

  /// Appends the frame's pose to trajectory.txt at once (flushed).
  void AddFrame(const FrameEstimate& estimate);
  /// Overwrites the poses of the frames with these stamps (an offline
  /// policy's final estimates); timing rows stay.
  void ReplaceEstimates(const std::vector<FrameEstimate>& estimates);
  /// The estimated poses so far (t, p_w_b, q_w_b).
  const std::vector<GroundTruthState>& trajectory() const { return trajectory_; }

  /// Replaces trajectory.txt by every frame's pose as it is now (atomically).
  void WriteTrajectory();
  /// timing.csv; a refinement that ran adds a last comment line with its cost.
  void WriteTiming(const RefinementReport& refinement) const;
  void WriteSummary(const RunResult& result, const std::string& frontend_json, const RunRequest& request,
                    double peak_memory_mb, const std::string& waiting_reason) const;
  void WriteConfig(const std::string& yaml) const;
  /// covariance.csv, one row per frame with a covariance:
  ///   #t_ns, then the upper triangle of the 6x6 pose covariance row by row
  ///   (pose_r_c, r <= c, over [dp_x dp_y dp_z (world, m), dth_x dth_y dth_z
  ///   (body, rad)]: 21 columns), then the variances of v_w_b (m/s)^2, b_g
  ///   (rad/s)^2, b_a (m/s^2)^2 (9 columns).
  void AddCovariance(const StateCovariance& covariance);
  void WriteCovariance() const;
  /// The pose blocks of the covariances added so far.
  std::vector<PoseCovariance> PoseCovariances() const;
  void WriteNees(const NeesResult& nees) const;

 private:
  std::string dir_;
  std::ofstream streamed_;  ///< trajectory.txt while the frames are estimated
  std::vector<GroundTruthState> trajectory_;
  std::vector<FrameEstimate> frames_;
  std::vector<StateCovariance> covariances_;
};

}  // namespace vio::tools
