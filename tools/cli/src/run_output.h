#pragma once
// The files of one run's output folder (see run.h). Private to tools.
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

  void AddFrame(const FrameEstimate& estimate);
  /// Overwrites the poses of the frames with these stamps (an offline
  /// policy's final estimates); timing rows stay.
  void ReplaceEstimates(const std::vector<FrameEstimate>& estimates);
  /// The estimated poses so far (t, p_w_b, q_w_b).
  const std::vector<GroundTruthState>& trajectory() const { return trajectory_; }

  void WriteTrajectory() const;
  void WriteTiming() const;
  void WriteSummary(const RunResult& result, const std::string& frontend_json, const RunRequest& request,
                    double peak_memory_mb, const std::string& waiting_reason) const;
  void WriteConfig(const std::string& yaml) const;

 private:
  std::string dir_;
  std::vector<GroundTruthState> trajectory_;
  std::vector<FrameEstimate> frames_;
};

}  // namespace vio::tools
