// Random linear-Gaussian instances of every filter step of the equivalence
// theorems: h(x, f) = H_x x + H_f f, g(x) = G x + u, Euclidean blocks.
#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <numeric>
#include <random>
#include <utility>
#include <vector>

#include "equivalence_internal.h"
#include "vio/marginalization/equivalence.h"

namespace vio::marginalization {
namespace {

class Random {
 public:
  explicit Random(unsigned seed) : engine_(seed) {}

  Eigen::MatrixXd Matrix(Eigen::Index rows, Eigen::Index cols) {
    return Eigen::MatrixXd::NullaryExpr(rows, cols, [this] { return normal_(engine_); });
  }
  Eigen::VectorXd Vector(Eigen::Index size) { return Matrix(size, 1); }
  double Uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(engine_); }
  int Integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(engine_); }
  /// 0..n-1 in random order.
  std::vector<int> Permutation(int n) {
    std::vector<int> permutation(static_cast<size_t>(n));
    std::iota(permutation.begin(), permutation.end(), 0);
    std::shuffle(permutation.begin(), permutation.end(), engine_);
    return permutation;
  }

  Eigen::MatrixXd Orthogonal(Eigen::Index n) {
    return Eigen::HouseholderQR<Eigen::MatrixXd>(Matrix(n, n)).householderQ();
  }
  /// U diag(s) V^T with singular values s in [lo, hi]: a well-conditioned matrix.
  Eigen::MatrixXd Conditioned(Eigen::Index n, double lo, double hi) {
    Eigen::VectorXd s(n);
    for (Eigen::Index i = 0; i < n; ++i) s(i) = Uniform(lo, hi);
    return Orthogonal(n) * s.asDiagonal() * Orthogonal(n).transpose();
  }
  /// A correlated covariance with eigenvalues in [0.1, 1] * scale.
  Eigen::MatrixXd Covariance(Eigen::Index n, double scale) {
    const Eigen::MatrixXd Q = Orthogonal(n);
    Eigen::VectorXd lambda(n);
    for (Eigen::Index i = 0; i < n; ++i) lambda(i) = scale * Uniform(0.1, 1.0);
    const Eigen::MatrixXd Sigma = Q * lambda.asDiagonal() * Q.transpose();
    return 0.5 * (Sigma + Sigma.transpose());
  }

 private:
  std::mt19937 engine_;
  std::normal_distribution<double> normal_;
};

StateLayout EuclideanBlocks(int first_size, int count, int size) {
  StateLayout layout;
  if (first_size > 0) layout.AddEuclidean(first_size);
  for (int i = 0; i < count; ++i) layout.AddEuclidean(size);
  return layout;
}

Gaussian RandomGaussian(const StateLayout& layout, Random* random) {
  return {random->Vector(layout.AmbientSize()), random->Covariance(layout.TangentSize(), 1.0)};
}

/// The filter state of the MSCKF: (x_IMU = [pose d_x, rest], x_1..x_n).
StateLayout MsckfLayout(const LinearProblemSizes& sizes) {
  StateLayout layout;
  layout.AddEuclidean(sizes.robot_dim).AddEuclidean(sizes.imu_dim - sizes.robot_dim);
  return layout.Append(EuclideanBlocks(0, sizes.num_poses, sizes.robot_dim));
}

EkfAugmentationProblem LinearEkfAugmentation(const LinearProblemSizes& sizes, Random* random) {
  const int d_x = sizes.robot_dim, d_f = sizes.feature_dim, p_new = sizes.num_new_features;
  EkfAugmentationProblem problem;
  problem.layout = EuclideanBlocks(d_x, sizes.num_features, d_f);
  problem.robot_dim = d_x;
  problem.state = RandomGaussian(problem.layout, random);
  problem.new_feature_layout = EuclideanBlocks(0, p_new, d_f);
  const Eigen::VectorXd mu_x = problem.state.mean.head(d_x);
  const Eigen::Index m = p_new * d_f;
  LinearizedMeasurements& meas = problem.measurements;
  meas.H_x = random->Matrix(m, d_x);
  meas.H_f = meas.Sigma_v = Eigen::MatrixXd::Zero(m, m);
  problem.L_z = Eigen::MatrixXd::Zero(m, m);
  for (int k = 0; k < p_new; ++k) {  // z_k = H_x x + H_f,k f_k + v: ℓ(x, z) = H_f,k^-1 (z - H_x x)
    meas.H_f.block(k * d_f, k * d_f, d_f, d_f) = random->Conditioned(d_f, 0.5, 2.0);
    meas.Sigma_v.block(k * d_f, k * d_f, d_f, d_f) = random->Covariance(d_f, 0.1);
    problem.L_z.block(k * d_f, k * d_f, d_f, d_f) = meas.H_f.block(k * d_f, k * d_f, d_f, d_f).inverse();
  }
  const Eigen::VectorXd z = random->Vector(m);
  problem.L_x = -problem.L_z * meas.H_x;
  problem.new_feature_means = problem.L_z * (z - meas.H_x * mu_x);
  meas.innovation = z - meas.H_x * mu_x - meas.H_f * problem.new_feature_means;
  return problem;
}

EkfUpdateProblem LinearEkfUpdate(const LinearProblemSizes& sizes, Random* random) {
  const int d_x = sizes.robot_dim, d_f = sizes.feature_dim, p = sizes.num_features;
  EkfUpdateProblem problem;
  problem.layout = EuclideanBlocks(d_x, p, d_f);
  problem.state = RandomGaussian(problem.layout, random);
  const Eigen::Index m = p * d_f;
  LinearizedMeasurements& meas = problem.measurements;
  meas.H_x = Eigen::MatrixXd::Zero(m, problem.layout.TangentSize());
  meas.Sigma_v = Eigen::MatrixXd::Zero(m, m);
  for (int k = 0; k < p; ++k) {  // z_k = H_x x + H_f f_k + v
    meas.H_x.block(k * d_f, 0, d_f, d_x) = random->Matrix(d_f, d_x);
    meas.H_x.block(k * d_f, d_x + k * d_f, d_f, d_f) = random->Matrix(d_f, d_f);
    meas.Sigma_v.block(k * d_f, k * d_f, d_f, d_f) = random->Covariance(d_f, 0.1);
  }
  meas.innovation = random->Vector(m);
  return problem;
}

/// x_{t+1} = G x_t + u: the filter's (g(μ̄_x), G) and the cost's r = x_{t+1} - g(x_t).
PropagationProblem LinearPropagation(const StateLayout& layout, int robot_blocks, int cloned_blocks,
                                     Random* random) {
  PropagationProblem problem;
  problem.layout = layout;
  problem.robot_blocks = robot_blocks;
  problem.cloned_blocks = cloned_blocks;
  problem.state = RandomGaussian(layout, random);
  const int d_x = layout.Slice(0, robot_blocks).TangentSize();
  const Eigen::MatrixXd G = random->Conditioned(d_x, 0.5, 2.0);
  const Eigen::VectorXd u = random->Vector(d_x);
  const Eigen::VectorXd g_of_mean = G * problem.state.mean.head(d_x) + u;
  problem.dynamics = {g_of_mean, G, random->Covariance(d_x, 0.1)};
  problem.residual = {g_of_mean - (G * problem.state.mean.head(d_x) + u), -G,
                      Eigen::MatrixXd::Identity(d_x, d_x)};
  return problem;
}

MsckfUpdateProblem LinearMsckfUpdate(const LinearProblemSizes& sizes, Random* random) {
  const int d_x = sizes.robot_dim, d_f = sizes.feature_dim, n = sizes.num_poses;
  MsckfUpdateProblem problem;
  problem.layout = MsckfLayout(sizes);
  problem.state = RandomGaussian(problem.layout, random);
  problem.feature_layout = EuclideanBlocks(0, sizes.num_features, d_f);
  problem.feature_estimates = random->Vector(problem.feature_layout.AmbientSize());
  std::vector<std::pair<int, int>> observations;  // (pose i, feature j), each j from 2..n poses
  for (int j = 0; j < sizes.num_features; ++j) {
    const std::vector<int> poses = random->Permutation(n);
    const int count = random->Integer(2, n);
    for (int k = 0; k < count; ++k) observations.emplace_back(poses[k], j);
  }
  const Eigen::Index m = static_cast<Eigen::Index>(observations.size()) * d_f;
  LinearizedMeasurements& meas = problem.measurements;
  meas.H_x = Eigen::MatrixXd::Zero(m, problem.layout.TangentSize());
  meas.H_f = Eigen::MatrixXd::Zero(m, problem.feature_layout.TangentSize());
  meas.Sigma_v = Eigen::MatrixXd::Zero(m, m);
  for (size_t k = 0; k < observations.size(); ++k) {  // z_ij = H_i x_i + H_j f_j + v
    const auto [i, j] = observations[k];
    const Eigen::Index row = static_cast<Eigen::Index>(k) * d_f;
    meas.H_x.block(row, sizes.imu_dim + i * d_x, d_f, d_x) = random->Matrix(d_f, d_x);
    meas.H_f.block(row, j * d_f, d_f, d_f) = random->Matrix(d_f, d_f);
    meas.Sigma_v.block(row, row, d_f, d_f) = random->Covariance(d_f, 0.1);
  }
  meas.innovation = random->Vector(m);
  return problem;
}

void RequireSizes(const LinearProblemSizes& s) {
  VIO_REQUIRE_INPUT(s.robot_dim >= 1 && s.imu_dim > s.robot_dim && s.feature_dim >= 1);
  VIO_REQUIRE_INPUT(s.num_features >= 1 && s.num_new_features >= 1 && s.num_poses >= 2);
}

}  // namespace

EquivalenceProblems RandomLinearGaussianProblems(const LinearProblemSizes& sizes, unsigned seed) {
  RequireSizes(sizes);
  Random random(seed);
  EquivalenceProblems problems;
  problems.ekf_augmentation = LinearEkfAugmentation(sizes, &random);
  problems.ekf_update = LinearEkfUpdate(sizes, &random);
  problems.ekf_propagation =
      LinearPropagation(EuclideanBlocks(sizes.robot_dim, sizes.num_features, sizes.feature_dim),
                        /*robot_blocks=*/1, /*cloned_blocks=*/0, &random);
  problems.msckf_update = LinearMsckfUpdate(sizes, &random);
  problems.msckf_propagation =
      LinearPropagation(MsckfLayout(sizes), /*robot_blocks=*/2, /*cloned_blocks=*/1, &random);
  return problems;
}

}  // namespace vio::marginalization
