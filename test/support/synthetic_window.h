#pragma once
// A synthetic visual-inertial flight (the simulator's room, features at
// 0.5 px) and windows built from it, shared by the window tests and the
// micro-benchmarks. Header-only: it needs the simulator (vio_simulator), which
// the GoogleTest support library does not link.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "vio/estimator/imu_preintegration.h"
#include "vio/estimator/policy.h"
#include "vio/estimator/window.h"
#include "vio/frontend/stereo_rectifier.h"
#include "vio/simulator/simulator.h"
#include "vio/dataset/stereo_frames.h"

namespace vio::test {

class SyntheticFlight {
 public:
  SyntheticFlight(double duration_s, std::uint64_t seed) {
    tools::SimulatorOptions options;
    options.duration_s = duration_s;
    options.seed = seed;
    sim_ = tools::BuildSimulation(options);
    const frontend::StereoRectifier rectifier(sim_.dataset.cameras[0], sim_.dataset.cameras[1]);
    stereo_ = rectifier.rectified();
    tools::StereoFramesReport report;
    frames_ = tools::StereoFramesFromFeatures(sim_.dataset.features, sim_.dataset.frames[0], rectifier, 2.0, &report);
  }

  const RectifiedStereo& stereo() const { return stereo_; }
  const std::vector<StereoFrame>& frames() const { return frames_; }
  const tools::Simulation& sim() const { return sim_; }

  /// The first ground-truth sample at or after t_ns (the last one past the end).
  const tools::GroundTruthState& GroundTruthAt(Timestamp t_ns) const {
    const auto& gt = sim_.dataset.groundtruth;
    auto it = std::lower_bound(gt.begin(), gt.end(), t_ns,
                               [](const tools::GroundTruthState& g, Timestamp t) { return g.t_ns < t; });
    return it == gt.end() ? gt.back() : *it;
  }

  /// The IMU preintegrated between frames k and k + 1 at zero bias.
  ImuPreintegration ImuBetween(int k) const {
    return PreintegrateBetween(sim_.dataset.imu, frames_[k].t_ns, frames_[k + 1].t_ns, ImuBias{},
                               sim_.dataset.imu_calibration);
  }

  /// States 0..count-1 at frames [first, first + count), at the ground truth
  /// with positions moved by +-position_offset_m (alternating), linked by IMU
  /// factors, a prior on the first, every observation added.
  void Build(Window& window, const ModelOptions& model, int first, int count, double position_offset_m = 0) const {
    for (int k = 0; k < count; ++k) {
      AddState(window, first, k, Eigen::Vector3d::Constant(k % 2 ? position_offset_m : -position_offset_m));
      AddStereoObservations(frames_[first + k], StateId(k), model, window);
    }
  }

  /// State k at frame first + k, at the ground truth moved by `offset_m`:
  /// the prior when k == 0, else the IMU factor from state k - 1.
  void AddState(Window& window, int first, int k, const Eigen::Vector3d& offset_m) const {
    const StereoFrame& frame = frames_[first + k];
    const tools::GroundTruthState& gt = GroundTruthAt(frame.t_ns);
    State& s = window.AddState(StateId(k), frame.t_ns);
    s.SetPose(gt.p_w_b + offset_m, gt.q_w_b);
    s.SetSpeedBias(gt.v_w_b, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
    if (k == 0) {
      StatePrior prior;
      prior.pose_covariance = Eigen::Matrix<double, 6, 6>::Identity() * 1e-6;
      prior.speed_bias_sigma << Eigen::Vector3d::Constant(0.1), Eigen::Vector3d::Constant(0.01),
          Eigen::Vector3d::Constant(0.1);
      window.AddStatePrior(StateId(k), prior);
    } else {
      window.AddImuFactor(StateId(k - 1), StateId(k), ImuBetween(first + k - 1));
    }
  }

 private:
  tools::Simulation sim_;
  std::vector<StereoFrame> frames_;
  RectifiedStereo stereo_;
};

}  // namespace vio::test
