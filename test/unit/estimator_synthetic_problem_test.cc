// A small visual-inertial window solved with Ceres: 3 states linked by IMU
// factors, 20 landmarks seen by stereo factors, the first pose held by a
// prior. Noise-free measurements, perturbed start: the solution must return
// to the ground truth.
#include <memory>
#include <random>
#include <vector>

#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include "estimator_test_support.h"
#include "vio/estimator/imu_factor.h"
#include "vio/estimator/imu_preintegration.h"
#include "vio/estimator/pose_manifold.h"
#include "vio/estimator/pose_prior_factor.h"
#include "vio/estimator/stereo_factor.h"

namespace vio {
namespace {

using test::MotionState;
using test::PoseBlock;
using test::RandomVector;
using test::SpeedBiasBlock;

constexpr int kNumStates = 3;
constexpr int kNumLandmarks = 20;
constexpr double kSigmaPx = 1.0;
const Eigen::Vector3d kGravity(0.0, 0.0, -9.81);
const Eigen::Vector3d kGyroBias(0.01, -0.02, 0.015);
const Eigen::Vector3d kAccelBias(0.1, 0.05, -0.08);

/// A rectified rig whose left camera looks along the body x axis.
RectifiedStereo ForwardLookingStereo() {
  RectifiedStereo stereo;
  Eigen::Matrix3d R_b_c;
  R_b_c << 0, 0, 1,
           -1, 0, 0,
           0, -1, 0;
  stereo.T_b_cl.linear() = R_b_c;
  stereo.T_b_cl.translation() = Eigen::Vector3d(0.05, -0.02, 0.01);
  return stereo;
}

/// Ground truth and measurements of the window.
struct Scenario {
  test::SyntheticMotion motion;
  RectifiedStereo stereo = ForwardLookingStereo();
  std::vector<Timestamp> frame_ns;
  std::vector<MotionState> states;
  std::vector<Eigen::Vector3d> landmarks;
  std::vector<ImuSample> imu;

  Scenario() {
    motion.w0 = Eigen::Vector3d(0.1, -0.05, 0.2);
    for (int k = 0; k < kNumStates; ++k) {
      frame_ns.push_back(22'500'000 + k * 500'000'000LL);  // between IMU samples
      states.push_back(motion.At(NanosToSeconds(frame_ns.back())));
    }
    imu = motion.ImuSamples(0, frame_ns.back() + 10'000'000, 5'000'000, kGyroBias, kAccelBias);
    std::mt19937 rng(99);
    const MotionState& middle = states[1];
    while (static_cast<int>(landmarks.size()) < kNumLandmarks) {
      const Eigen::Vector3d p_c(RandomVector<1>(rng, 2.0)[0], RandomVector<1>(rng, 1.5)[0],
                                6.0 + RandomVector<1>(rng, 2.0)[0]);
      landmarks.push_back(middle.p_w_b + middle.q_w_b * (stereo.T_b_cl * p_c));
    }
  }

  Eigen::Vector3d Observe(int state, int landmark) const {
    Eigen::Vector3d z;
    EXPECT_TRUE(StereoFactor::Project(stereo, states[state].p_w_b, states[state].q_w_b, landmarks[landmark], &z))
        << "landmark " << landmark << " is behind state " << state;
    return z;
  }
};

/// The estimate: one block per variable.
struct Estimate {
  std::vector<std::vector<double>> poses, speed_biases, landmarks;
};

Estimate PerturbedTruth(const Scenario& scenario) {
  std::mt19937 rng(5);
  Estimate estimate;
  for (const MotionState& state : scenario.states) {
    estimate.poses.push_back(PoseBlock(state.p_w_b + RandomVector<3>(rng, 0.1),
                                       state.q_w_b * so3::ExpQuaternion(RandomVector<3>(rng, 0.05))));
    estimate.speed_biases.push_back(SpeedBiasBlock(state.v_w_b + RandomVector<3>(rng, 0.1),
                                                   Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()));
  }
  for (const Eigen::Vector3d& p_w_l : scenario.landmarks) {
    const Eigen::Vector3d perturbed = p_w_l + RandomVector<3>(rng, 0.2);
    estimate.landmarks.push_back({perturbed.x(), perturbed.y(), perturbed.z()});
  }
  return estimate;
}

ImuBias BiasOf(const std::vector<double>& speed_bias) {
  return ImuBias{Eigen::Vector3d(speed_bias[3], speed_bias[4], speed_bias[5]),
                 Eigen::Vector3d(speed_bias[6], speed_bias[7], speed_bias[8])};
}

/// Builds the window problem on `estimate` and solves it.
ceres::Solver::Summary Solve(const Scenario& scenario, const std::vector<ImuPreintegration>& imu,
                             Estimate* estimate) {
  ceres::Problem problem;
  const MotionState& first = scenario.states[0];
  problem.AddResidualBlock(PosePriorFactor::Create(first.p_w_b, first.q_w_b, 1e-3, 1e-3), nullptr,
                           estimate->poses[0].data());
  for (int k = 0; k + 1 < kNumStates; ++k) {
    problem.AddResidualBlock(ImuFactor::Create(imu[k], kGravity), nullptr, estimate->poses[k].data(),
                             estimate->speed_biases[k].data(), estimate->poses[k + 1].data(),
                             estimate->speed_biases[k + 1].data());
  }
  for (int k = 0; k < kNumStates; ++k) {
    for (int l = 0; l < kNumLandmarks; ++l) {
      problem.AddResidualBlock(StereoFactor::Create(scenario.Observe(k, l), scenario.stereo, kSigmaPx),
                               nullptr, estimate->poses[k].data(), estimate->landmarks[l].data());
    }
    problem.SetManifold(estimate->poses[k].data(), new PoseManifold);
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_SCHUR;
  options.max_num_iterations = 100;
  options.function_tolerance = 1e-20;
  options.gradient_tolerance = 1e-20;
  options.parameter_tolerance = 1e-20;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  return summary;
}

TEST(SyntheticWindow, ConvergesToTheGroundTruthFromAPerturbedStart) {
  const Scenario scenario;
  // Preintegrate at a wrong bias (zero); reintegrate at the estimate after a
  // first solve, as the window manager does when the bias moves too far.
  std::vector<ImuPreintegration> imu;
  for (int k = 0; k + 1 < kNumStates; ++k) {
    imu.push_back(PreintegrateBetween(scenario.imu, scenario.frame_ns[k], scenario.frame_ns[k + 1],
                                      ImuBias(), ImuCalibration()));
  }
  Estimate estimate = PerturbedTruth(scenario);
  const ceres::Solver::Summary first = Solve(scenario, imu, &estimate);
  ASSERT_TRUE(first.IsSolutionUsable()) << first.FullReport();
  for (int k = 0; k + 1 < kNumStates; ++k) {
    ASSERT_TRUE(imu[k].NeedsReintegration(BiasOf(estimate.speed_biases[k]), 1e-3, 1e-2));
    imu[k].Reintegrate(BiasOf(estimate.speed_biases[k]));
  }
  const ceres::Solver::Summary second = Solve(scenario, imu, &estimate);
  ASSERT_TRUE(second.IsSolutionUsable()) << second.FullReport();
  EXPECT_LT(second.final_cost, 1e-12);

  for (int k = 0; k < kNumStates; ++k) {
    const MotionState& truth = scenario.states[k];
    const auto& pose = estimate.poses[k];
    const auto& speed_bias = estimate.speed_biases[k];
    const Eigen::Quaterniond q(pose[6], pose[3], pose[4], pose[5]);
    EXPECT_LT((Eigen::Vector3d(pose[0], pose[1], pose[2]) - truth.p_w_b).norm(), 1e-6) << "state " << k;
    EXPECT_LT(so3::Log(truth.q_w_b.conjugate() * q).norm(), 1e-6) << "state " << k;
    EXPECT_LT((Eigen::Vector3d(speed_bias[0], speed_bias[1], speed_bias[2]) - truth.v_w_b).norm(), 1e-5);
    EXPECT_LT((BiasOf(speed_bias).gyro - kGyroBias).norm(), 1e-5) << "state " << k;
    EXPECT_LT((BiasOf(speed_bias).accel - kAccelBias).norm(), 1e-4) << "state " << k;
  }
  for (int l = 0; l < kNumLandmarks; ++l) {
    const auto& p = estimate.landmarks[l];
    EXPECT_LT((Eigen::Vector3d(p[0], p[1], p[2]) - scenario.landmarks[l]).norm(), 1e-6) << "landmark " << l;
  }
}

}  // namespace
}  // namespace vio
