// Small nonlinear instances of every filter step of the equivalence theorems
// (see vio/verify/verify.h): a true scene (SE3 body poses with body
// velocities, landmarks 3-8 m in front of the camera), noisy stereo
// measurements of it, and a filter state around it (mean = truth ⊞ a draw of
// a random correlated covariance), linearized at the filter's estimate.
#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <algorithm>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "nonlinear_models.h"
#include "vio/estimator/so3.h"
#include "vio/verify/verify.h"

namespace vio::tools {
namespace {

using marginalization::EkfAugmentationProblem;
using marginalization::EkfUpdateProblem;
using marginalization::Gaussian;
using marginalization::MsckfUpdateProblem;
using marginalization::PropagationProblem;
using marginalization::StateLayout;
using namespace verify_models;

// Standard deviations of the filter state and of the process noise.
constexpr double kPositionSigma = 0.05;  // [m]
constexpr double kRotationSigma = 0.02;  // [rad]
constexpr double kVelocitySigma = 0.1;   // [m/s]
constexpr double kLandmarkSigma = 0.1;   // [m]
constexpr double kProcessPositionSigma = 0.01, kProcessRotationSigma = 0.005, kProcessVelocitySigma = 0.05;

class Random {
 public:
  explicit Random(unsigned seed) : engine_(seed) {}
  double Uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(engine_); }
  int Integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(engine_); }
  Eigen::VectorXd Normal(Eigen::Index n) {
    return Eigen::VectorXd::NullaryExpr(n, [this] { return normal_(engine_); });
  }
  Eigen::Vector3d Uniform3(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
    return {Uniform(lo.x(), hi.x()), Uniform(lo.y(), hi.y()), Uniform(lo.z(), hi.z())};
  }
  std::vector<int> Permutation(int n) {
    std::vector<int> permutation(static_cast<size_t>(n));
    std::iota(permutation.begin(), permutation.end(), 0);
    std::shuffle(permutation.begin(), permutation.end(), engine_);
    return permutation;
  }
  /// D C D: standard deviations `sigma`, correlations C of a random
  /// covariance with eigenvalues in [0.2, 1].
  Eigen::MatrixXd Covariance(const Eigen::VectorXd& sigma) {
    const Eigen::Index n = sigma.size();
    const Eigen::MatrixXd Q =
        Eigen::HouseholderQR<Eigen::MatrixXd>(Eigen::MatrixXd(Eigen::MatrixXd::NullaryExpr(n, n, [this] {
          return normal_(engine_);
        }))).householderQ();
    Eigen::VectorXd lambda(n);
    for (Eigen::Index i = 0; i < n; ++i) lambda(i) = Uniform(0.2, 1.0);
    const Eigen::MatrixXd S = Q * lambda.asDiagonal() * Q.transpose();
    const Eigen::VectorXd scale = sigma.cwiseQuotient(S.diagonal().cwiseSqrt());
    const Eigen::MatrixXd Sigma = scale.asDiagonal() * S * scale.asDiagonal();
    return 0.5 * (Sigma + Sigma.transpose());
  }

 private:
  std::mt19937 engine_;
  std::normal_distribution<double> normal_;
};

// ---------------------------------------------------------------------------
// Truth, layouts, and the filter state around the truth.

/// [p_w_b, q_w_b, v_b]: near the origin, any heading, slightly tilted, moving forward.
Eigen::VectorXd TrueRobotState(Random* random) {
  const Eigen::Vector3d p_w_b = random->Uniform3({-1, -1, 0.5}, {1, 1, 1.5});
  const Eigen::Quaterniond q_w_b =
      so3::ExpQuaternion({0.0, 0.0, random->Uniform(-3.1, 3.1)}) *
      so3::ExpQuaternion({random->Uniform(-0.1, 0.1), random->Uniform(-0.1, 0.1), 0.0});
  Eigen::VectorXd x(kStateAmbient);
  x << PoseVector(p_w_b, q_w_b), random->Uniform3({0.5, -0.3, -0.2}, {1.5, 0.3, 0.2});
  return x;
}

/// A pose `forward` metres ahead of `pose` (body x), slightly shifted and turned.
Eigen::VectorXd NearbyPose(const Eigen::VectorXd& pose, double forward, Random* random) {
  const Eigen::Quaterniond q_w_b = Rotation(pose);
  const Eigen::Vector3d p_b = {forward, random->Uniform(-0.1, 0.1), random->Uniform(-0.05, 0.05)};
  return PoseVector(pose.head<3>() + q_w_b * p_b,
                    q_w_b * so3::ExpQuaternion(random->Uniform3({-0.05, -0.05, -0.05}, {0.05, 0.05, 0.05})));
}

/// A landmark 3-8 m ahead of the body (the camera looks along body x).
Eigen::Vector3d LandmarkInFront(const Eigen::VectorXd& pose, Random* random) {
  return pose.head<3>() + Rotation(pose) * random->Uniform3({3, -2, -1.5}, {8, 2, 1.5});
}

Eigen::Vector3d Measure(const Eigen::VectorXd& pose, const Eigen::Vector3d& p_w_l, Random* random) {
  return Project(pose, p_w_l) + kSigmaPx * random->Normal(3);
}

Eigen::VectorXd RobotSigma() {
  Eigen::VectorXd sigma(kStateTangent);
  sigma << Eigen::Vector3d::Constant(kPositionSigma), Eigen::Vector3d::Constant(kRotationSigma),
      Eigen::Vector3d::Constant(kVelocitySigma);
  return sigma;
}

Eigen::MatrixXd ProcessNoise(Random* random) {
  Eigen::VectorXd sigma(kStateTangent);
  sigma << Eigen::Vector3d::Constant(kProcessPositionSigma), Eigen::Vector3d::Constant(kProcessRotationSigma),
      Eigen::Vector3d::Constant(kProcessVelocitySigma);
  return random->Covariance(sigma);
}

/// Layout, true ambient state and tangent standard deviations of a filter state.
struct TrueState {
  StateLayout layout;
  Eigen::VectorXd truth;
  Eigen::VectorXd sigma;

  void Add(const Eigen::VectorXd& block_truth, const Eigen::VectorXd& block_sigma) {
    truth.conservativeResize(truth.size() + block_truth.size());
    truth.tail(block_truth.size()) = block_truth;
    sigma.conservativeResize(sigma.size() + block_sigma.size());
    sigma.tail(block_sigma.size()) = block_sigma;
  }
  void AddRobot(const Eigen::VectorXd& x) {
    layout.AddManifold(&Manifold()).AddEuclidean(3);
    Add(x, RobotSigma());
  }
  void AddPose(const Eigen::VectorXd& pose) {
    layout.AddManifold(&Manifold());
    Add(pose, RobotSigma().head(6));
  }
  void AddLandmark(const Eigen::Vector3d& p_w_l) {
    layout.AddEuclidean(3);
    Add(p_w_l, Eigen::Vector3d::Constant(kLandmarkSigma));
  }
};

/// The EKF state (x, f_1..f_p): landmarks in front of the robot.
TrueState EkfTruth(int num_features, Random* random) {
  TrueState truth;
  const Eigen::VectorXd robot = TrueRobotState(random);
  truth.AddRobot(robot);
  for (int k = 0; k < num_features; ++k) truth.AddLandmark(LandmarkInFront(robot, random));
  return truth;
}

/// N(truth ⊞ δ, Σ) with δ ~ N(0, Σ), Σ random with the state's standard deviations.
Gaussian AroundTruth(const TrueState& state, Random* random) {
  const Eigen::MatrixXd Sigma = random->Covariance(state.sigma);
  const Eigen::LLT<Eigen::MatrixXd> llt(Sigma);
  return {state.layout.Plus(state.truth, llt.matrixL() * random->Normal(state.sigma.size())), Sigma};
}

// ---------------------------------------------------------------------------
// The problems.

EkfAugmentationProblem NonlinearEkfAugmentation(int num_features, int num_new, Random* random) {
  const TrueState truth = EkfTruth(num_features, random);
  const Eigen::VectorXd robot = truth.truth.head(kStateAmbient);
  EkfAugmentationProblem problem;
  problem.layout = truth.layout;
  problem.robot_dim = kStateTangent;
  problem.state = AroundTruth(truth, random);
  const Eigen::VectorXd mean_pose = problem.state.mean.head(7);
  const int m = 3 * num_new;
  problem.new_feature_means.resize(m);
  problem.L_x = Eigen::MatrixXd::Zero(m, kStateTangent);
  problem.L_z = Eigen::MatrixXd::Zero(m, m);
  marginalization::LinearizedMeasurements& meas = problem.measurements;
  meas.innovation.resize(m);
  meas.H_x = Eigen::MatrixXd::Zero(m, kStateTangent);
  meas.H_f = Eigen::MatrixXd::Zero(m, m);
  meas.Sigma_v = kSigmaPx * kSigmaPx * Eigen::MatrixXd::Identity(m, m);
  for (int k = 0; k < num_new; ++k) {
    problem.new_feature_layout.AddEuclidean(3);
    const Eigen::Vector3d z = Measure(robot, LandmarkInFront(robot, random), random);
    const InverseMeasurement inverse = Triangulate(mean_pose, z);  // ℓ(μ_x, z)
    problem.new_feature_means.segment<3>(3 * k) = inverse.p_w_l;
    problem.L_x.block<3, 6>(3 * k, 0) = inverse.L_pose;
    problem.L_z.block<3, 3>(3 * k, 3 * k) = inverse.L_z;
    const StereoLinearization h = LinearizeStereo(z, mean_pose, inverse.p_w_l);
    meas.innovation.segment<3>(3 * k) = h.innovation;
    meas.H_x.block<3, 6>(3 * k, 0) = h.H_pose;
    meas.H_f.block<3, 3>(3 * k, 3 * k) = h.H_f;
  }
  return problem;
}

EkfUpdateProblem NonlinearEkfUpdate(int num_features, Random* random) {
  const TrueState truth = EkfTruth(num_features, random);
  EkfUpdateProblem problem;
  problem.layout = truth.layout;
  problem.state = AroundTruth(truth, random);
  const int m = 3 * num_features;
  marginalization::LinearizedMeasurements& meas = problem.measurements;
  meas.innovation.resize(m);
  meas.H_x = Eigen::MatrixXd::Zero(m, problem.layout.TangentSize());
  meas.Sigma_v = kSigmaPx * kSigmaPx * Eigen::MatrixXd::Identity(m, m);
  for (int k = 0; k < num_features; ++k) {  // at μ: pose μ_x, landmark μ_f,k
    const Eigen::Vector3d z =
        Measure(truth.truth.head(7), truth.truth.segment<3>(kStateAmbient + 3 * k), random);
    const StereoLinearization h =
        LinearizeStereo(z, problem.state.mean.head(7), problem.state.mean.segment<3>(kStateAmbient + 3 * k));
    meas.innovation.segment<3>(3 * k) = h.innovation;
    meas.H_x.block<3, 6>(3 * k, 0) = h.H_pose;
    meas.H_x.block<3, 3>(3 * k, kStateTangent + 3 * k) = h.H_f;
  }
  return problem;
}

/// The filter state around `truth` and the motion linearized at its mean:
/// the filter's (g(μ̄_x), G) and the cost's r = x_{t+1} ⊟ g(x_t) at (μ̄_x, g(μ̄_x)).
PropagationProblem NonlinearPropagation(const TrueState& truth, int robot_blocks, int cloned_blocks,
                                        Random* random) {
  PropagationProblem problem;
  problem.layout = truth.layout;
  problem.robot_blocks = robot_blocks;
  problem.cloned_blocks = cloned_blocks;
  problem.state = AroundTruth(truth, random);
  const Motion motion{so3::ExpQuaternion(random->Uniform3({-0.1, -0.1, -0.1}, {0.1, 0.1, 0.1}))};
  const Eigen::VectorXd x_t = problem.state.mean.head(kStateAmbient);
  const Eigen::VectorXd g_of_mean = Propagate(motion, x_t);
  problem.dynamics = {g_of_mean, MotionJacobian(motion, x_t), ProcessNoise(random)};
  problem.residual = MotionResidualAt(motion, x_t, g_of_mean);
  return problem;
}

/// The MSCKF state: the IMU state 1.2 m ahead of the first of n poses spread
/// over the metre before it.
TrueState MsckfTruth(int num_poses, const Eigen::VectorXd& first_pose, Random* random) {
  TrueState truth;
  Eigen::VectorXd imu = TrueRobotState(random);
  imu.head(7) = NearbyPose(first_pose, 1.2, random);
  truth.AddRobot(imu);
  for (int i = 0; i < num_poses; ++i) truth.AddPose(NearbyPose(first_pose, i * 1.0 / num_poses, random));
  return truth;
}

/// One observation of the MSCKF update: pose i sees feature j.
struct Observation {
  int pose;
  int feature;
  StereoLinearization h;
};

MsckfUpdateProblem AssembleMsckfUpdate(MsckfUpdateProblem problem,
                                       const std::vector<Observation>& observations) {
  const int m = 3 * static_cast<int>(observations.size());
  marginalization::LinearizedMeasurements& meas = problem.measurements;
  meas.innovation.resize(m);
  meas.H_x = Eigen::MatrixXd::Zero(m, problem.layout.TangentSize());
  meas.H_f = Eigen::MatrixXd::Zero(m, problem.feature_layout.TangentSize());
  meas.Sigma_v = kSigmaPx * kSigmaPx * Eigen::MatrixXd::Identity(m, m);
  for (int k = 0; k < static_cast<int>(observations.size()); ++k) {
    const Observation& o = observations[k];
    meas.innovation.segment<3>(3 * k) = o.h.innovation;
    meas.H_x.block<3, 6>(3 * k, kStateTangent + 6 * o.pose) = o.h.H_pose;
    meas.H_f.block<3, 3>(3 * k, 3 * o.feature) = o.h.H_f;
  }
  return problem;
}

// Each feature is seen from 2..n random poses; f* is triangulated from its
// first observation at that pose's estimate; all linearized at (μ, f*).
MsckfUpdateProblem NonlinearMsckfUpdate(int num_features, int num_poses, Random* random) {
  const Eigen::VectorXd first_pose = TrueRobotState(random).head(7);
  const TrueState truth = MsckfTruth(num_poses, first_pose, random);
  MsckfUpdateProblem problem;
  problem.layout = truth.layout;
  problem.state = AroundTruth(truth, random);
  problem.feature_estimates.resize(3 * num_features);
  auto true_pose = [&](int i) { return truth.truth.segment<7>(kStateAmbient + 7 * i).eval(); };
  auto mean_pose = [&](int i) { return problem.state.mean.segment<7>(kStateAmbient + 7 * i).eval(); };
  std::vector<Observation> observations;
  for (int j = 0; j < num_features; ++j) {
    problem.feature_layout.AddEuclidean(3);
    const Eigen::Vector3d p_w_l = LandmarkInFront(first_pose, random);
    const std::vector<int> poses = random->Permutation(num_poses);
    const int count = random->Integer(2, num_poses);
    std::vector<Eigen::Vector3d> z;
    for (int k = 0; k < count; ++k) z.push_back(Measure(true_pose(poses[k]), p_w_l, random));
    const Eigen::Vector3d f_star = Triangulate(mean_pose(poses[0]), z[0]).p_w_l;
    problem.feature_estimates.segment<3>(3 * j) = f_star;
    for (int k = 0; k < count; ++k) {
      observations.push_back({poses[k], j, LinearizeStereo(z[k], mean_pose(poses[k]), f_star)});
    }
  }
  return AssembleMsckfUpdate(std::move(problem), observations);
}

}  // namespace

marginalization::EquivalenceProblems RandomNonlinearProblems(const NonlinearProblemSizes& sizes,
                                                             unsigned seed) {
  if (sizes.num_landmarks < 1 || sizes.num_landmarks > 50 || sizes.num_poses < 2 || sizes.num_poses > 20) {
    throw std::invalid_argument(std::string(__FILE__) +
                                ": num_landmarks must be in [1, 50] and num_poses in "
                                "[2, 20], got " +
                                std::to_string(sizes.num_landmarks) + " and " +
                                std::to_string(sizes.num_poses));
  }
  Random random(seed);
  const int p = sizes.num_landmarks, n = sizes.num_poses;
  marginalization::EquivalenceProblems problems;
  problems.ekf_augmentation = NonlinearEkfAugmentation(p, std::max(1, p / 2), &random);
  problems.ekf_update = NonlinearEkfUpdate(p, &random);
  problems.ekf_propagation =
      NonlinearPropagation(EkfTruth(p, &random), /*robot_blocks=*/2, /*cloned_blocks=*/0, &random);
  problems.msckf_update = NonlinearMsckfUpdate(p, n, &random);
  const TrueState msckf_truth = MsckfTruth(n, TrueRobotState(&random).head(7), &random);
  problems.msckf_propagation =
      NonlinearPropagation(msckf_truth, /*robot_blocks=*/2, /*cloned_blocks=*/1, &random);
  return problems;
}

}  // namespace vio::tools
