// First-estimate Jacobians keep the unobservable directions of VIO
// unobservable. A window of 8 states on the synthetic flight with no absolute
// prior (so position and yaw are unobservable), its oldest state
// marginalized (a prior on its Markov blanket, linearized there), then every
// estimate moved (a relinearization). The window's information (the reduced
// Gauss-Newton system over the states and the landmarks the prior ties)
// must have the 4-dimensional null space N = [global translation, yaw about
// gravity], each direction at the point the Jacobians of its block are
// taken: the prior's linearization point for the blocks in the prior, the
// current estimate for the others. With FEJ it does, to 1e-8 relative;
// without, the yaw direction is lost (translation stays unobservable at any
// linearization point).
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include "synthetic_window.h"
#include "vio/estimator/so3.h"
#include "vio/estimator/window.h"
#include "vio/marginalization/marginalization_prior.h"

namespace vio {
namespace {

constexpr int kFrames = 8;
constexpr int kFirst = 60;

const test::SyntheticFlight& Flight() {
  static const test::SyntheticFlight flight(6.0, 7);
  return flight;
}

ModelOptions Model(bool fej) {
  ModelOptions model;
  model.huber_px = 0;
  model.fej = fej;
  return model;
}

/// States 0..kFrames-1 at the ground truth +-1 cm, IMU factors, every
/// observation; no prior on the first state.
void BuildWithoutAbsolutePrior(Window& window, const ModelOptions& model) {
  for (int k = 0; k < kFrames; ++k) {
    const Eigen::Vector3d offset = Eigen::Vector3d::Constant(k % 2 ? 0.01 : -0.01);
    if (k == 0) {
      const StereoFrame& frame = Flight().frames()[kFirst];
      const tools::GroundTruthState& gt = Flight().GroundTruthAt(frame.t_ns);
      State& s = window.AddState(StateId(0), frame.t_ns);
      s.SetPose(gt.p_w_b + offset, gt.q_w_b);
      s.SetSpeedBias(gt.v_w_b, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
    } else {
      Flight().AddState(window, kFirst, k, offset);
    }
    AddStereoObservations(Flight().frames()[kFirst + k], StateId(k), model, window);
  }
}

/// Moves every state and landmark: positions and velocities by up to 5 cm
/// (/s), rotations by up to 0.02 rad.
void Relinearize(Window& window) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  const auto random3 = [&](double scale) -> Eigen::Vector3d {
    return Eigen::Vector3d(u(rng), u(rng), u(rng)) * scale;
  };
  for (const auto& [id, s] : window.states()) {
    State& state = window.state(id);
    state.SetPose(s.p_w_b() + random3(0.05), s.q_w_b() * so3::ExpQuaternion(random3(0.02)));
    state.SetSpeedBias(s.v_w_b() + random3(0.05), s.gyro_bias(), s.accel_bias());
  }
  for (const auto& [id, l] : window.landmarks()) {
    Eigen::Map<Eigen::Vector3d>(const_cast<double*>(l.p_w)) += random3(0.05);
  }
}

/// The linearization point of every block in a marginalization prior.
std::map<const double*, std::vector<double>> PriorPoints(ceres::Problem& problem) {
  std::vector<ceres::ResidualBlockId> residuals;
  problem.GetResidualBlocks(&residuals);
  std::map<const double*, std::vector<double>> points;
  for (ceres::ResidualBlockId id : residuals) {
    const auto* prior =
        dynamic_cast<const marginalization::MarginalizationPrior*>(problem.GetCostFunctionForResidualBlock(id));
    if (prior == nullptr) continue;
    std::vector<double*> blocks;
    problem.GetParameterBlocksForResidualBlock(id, &blocks);
    for (size_t i = 0; i < blocks.size(); ++i) points[blocks[i]] = prior->linearization_point(static_cast<int>(i));
  }
  return points;
}

/// N (dense columns x 4): x, y, z translation and yaw about world z, each
/// block at its linearization point.
Eigen::MatrixXd NullSpace(Window& window, const GaussNewtonLayout& layout) {
  const std::map<const double*, std::vector<double>> prior_points = PriorPoints(window.problem());
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  int rows = 0;
  for (const double* block : layout.dense) rows += window.problem().ParameterBlockTangentSize(block);
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(rows, 4);
  int row = 0;
  for (const double* block : layout.dense) {
    const auto it = prior_points.find(block);
    const double* x = it == prior_points.end() ? block : it->second.data();
    const int size = window.problem().ParameterBlockTangentSize(block);
    const Eigen::Map<const Eigen::Vector3d> head(x);
    if (size == 6) {  // pose [dp world, dtheta body]
      const Eigen::Quaterniond q(x[6], x[3], x[4], x[5]);
      N.block<3, 3>(row, 0).setIdentity();
      N.block<3, 1>(row, 3) = z.cross(head);
      N.block<3, 1>(row + 3, 3) = q.toRotationMatrix().transpose() * z;
    } else if (size == 9) {  // [v, b_g, b_a]
      N.block<3, 1>(row, 3) = z.cross(head);
    } else {  // landmark
      N.block<3, 3>(row, 0).setIdentity();
      N.block<3, 1>(row, 3) = z.cross(head);
    }
    row += size;
  }
  return N;
}

/// |H n| / (|H| |n|) of the translation (3) and yaw (1) directions.
Eigen::Vector4d NullSpaceResiduals(bool fej) {
  const ModelOptions model = Model(fej);
  Window window(model, Flight().stereo());
  BuildWithoutAbsolutePrior(window, model);
  window.Marginalize({StateId(0)}, {});
  EXPECT_EQ(window.num_priors(), 1);
  Relinearize(window);
  const GaussNewtonLayout layout = window.Layout();
  ReducedSystem system;
  EXPECT_TRUE(ReducedNormalEquations(&window.problem(), layout, &system));
  const Eigen::MatrixXd N = NullSpace(window, layout);
  EXPECT_GT(static_cast<int>(layout.dense.size()), 2 * (kFrames - 1));  // landmarks tied by the prior
  Eigen::Vector4d relative;
  for (int k = 0; k < 4; ++k) relative[k] = (system.H * N.col(k)).norm() / (system.H.norm() * N.col(k).norm());
  return relative;
}

TEST(WindowFej, UnobservableSubspaceStaysInTheNullSpaceWithFej) {
  const Eigen::Vector4d relative = NullSpaceResiduals(/*fej=*/true);
  for (int k = 0; k < 4; ++k) EXPECT_LE(relative[k], 1e-8) << "direction " << k << ": " << relative.transpose();
}

TEST(WindowFej, YawBecomesObservableWithoutFej) {
  const Eigen::Vector4d relative = NullSpaceResiduals(/*fej=*/false);
  for (int k = 0; k < 3; ++k) EXPECT_LE(relative[k], 1e-8) << "translation " << k << ": " << relative.transpose();
  // Measured: 1.6e-5 without FEJ, 1.5e-17 with it.
  EXPECT_GT(relative[3], 1e-6) << relative.transpose();
}

}  // namespace
}  // namespace vio
