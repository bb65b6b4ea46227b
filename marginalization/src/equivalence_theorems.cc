// The optimization forms of the filter sub-blocks (design paper, proofs of
// Theorems 6.2.1-6.2.5) and the checks that compare them with the reference
// filters.
#include <numeric>

#include "equivalence_internal.h"
#include "vio/marginalization/equivalence.h"

namespace vio::marginalization {
namespace {

/// `local` with its column i moved to column columns[i] of a `num_cols` wide
/// matrix (the cost's variable order); other columns zero.
Eigen::MatrixXd PlaceColumns(const Eigen::MatrixXd& local, const std::vector<Eigen::Index>& columns,
                             Eigen::Index num_cols) {
  Eigen::MatrixXd placed = Eigen::MatrixXd::Zero(local.rows(), num_cols);
  for (size_t i = 0; i < columns.size(); ++i)
    placed.col(columns[i]) = local.col(static_cast<Eigen::Index>(i));
  return placed;
}

std::vector<Eigen::Index> Range(Eigen::Index first, Eigen::Index count) {
  std::vector<Eigen::Index> range(static_cast<size_t>(count));
  std::iota(range.begin(), range.end(), first);
  return range;
}

/// The prior term ||x̃ ⊟ μ||²_Σ^-1 linearized at its mean x̃* = μ (as in every
/// theorem): r = μ ⊟ μ = 0 and ∂((μ ⊞ δ) ⊟ μ)/∂δ = I for any manifold
/// (Minus(Plus(x, δ), x) = δ). Tangent dimension i of x̃ is cost column columns[i].
ResidualTerm PriorTerm(const Gaussian& prior, const std::vector<Eigen::Index>& columns,
                       Eigen::Index num_cols) {
  const Eigen::Index d = prior.covariance.rows();
  VIO_REQUIRE_INPUT(static_cast<Eigen::Index>(columns.size()) == d);
  return {Eigen::VectorXd::Zero(d), PlaceColumns(Eigen::MatrixXd::Identity(d, d), columns, num_cols),
          prior.covariance};
}

/// The measurement term ||z̃ ⊟ h̃(x, f)||²_Σv^-1 linearized at (x*, f*):
/// r = innovation - H_x δ_x - H_f δ_f, with δ_x at `x_columns`, δ_f at `f_columns`.
ResidualTerm MeasurementTerm(const LinearizedMeasurements& m, const std::vector<Eigen::Index>& x_columns,
                             const std::vector<Eigen::Index>& f_columns, Eigen::Index num_cols) {
  Eigen::MatrixXd J = PlaceColumns(-m.H_x, x_columns, num_cols);
  if (!f_columns.empty()) J += PlaceColumns(-m.H_f, f_columns, num_cols);
  return {m.innovation, J, m.Sigma_v};
}

/// x_t (the first robot_blocks blocks), the rest, and x_t's cloned blocks.
struct PropagationSplit {
  StateLayout robot, rest, clone;
};

PropagationSplit Split(const PropagationProblem& problem) {
  const int num_blocks = static_cast<int>(problem.layout.blocks().size());
  VIO_REQUIRE_INPUT(problem.robot_blocks >= 1 && problem.robot_blocks <= num_blocks);
  VIO_REQUIRE_INPUT(problem.cloned_blocks >= 0 && problem.cloned_blocks < problem.robot_blocks);
  return {problem.layout.Slice(0, problem.robot_blocks),
          problem.layout.Slice(problem.robot_blocks, num_blocks - problem.robot_blocks),
          problem.layout.Slice(0, problem.cloned_blocks)};
}

EquivalenceCheck Finish(EquivalenceCheck check, const StateLayout& layout,
                        const Eigen::VectorXd& linearization_point) {
  check.deviation = Compare(check.optimization, check.filter, layout, linearization_point);
  return check;
}

/// ξ* of the kept variables of c_5: (g(μ̄_x), μ̄_rest[, μ̄_clone]).
Eigen::VectorXd KeptPropagationPoint(const PropagationProblem& problem, const PropagationSplit& split,
                                     bool keep_clone) {
  const Eigen::VectorXd& mean = problem.state.mean;
  const Eigen::Index a_x = split.robot.AmbientSize(), a_r = split.rest.AmbientSize();
  const Eigen::Index a_k = keep_clone ? split.clone.AmbientSize() : 0;
  VIO_REQUIRE_INPUT(problem.dynamics.g_of_mean.size() == a_x);
  Eigen::VectorXd point(a_x + a_r + a_k);
  point << problem.dynamics.g_of_mean, mean.segment(a_x, a_r), mean.head(a_k);
  return point;
}

}  // namespace

// Proof of Theorem 6.2.1: variables (x̃_t, f_new), C = [Σ^-1/2 (x̃ ⊟ μ);
// Σ̃v^-1/2 (z - h̃(x, f_new))], J = [Σ^-1/2 O; -Σ̃v^-1/2 H_x [I O]  -Σ̃v^-1/2 H_f].
Gaussian EkfAugmentationByGaussNewton(const EkfAugmentationProblem& problem) {
  const Eigen::Index d = problem.layout.TangentSize();
  const Eigen::Index d_new = problem.new_feature_layout.TangentSize();
  StateLayout layout = problem.layout;
  layout.Append(problem.new_feature_layout);
  Eigen::VectorXd linearization_point(layout.AmbientSize());
  linearization_point << problem.state.mean, problem.new_feature_means;
  const std::vector<ResidualTerm> terms = {
      PriorTerm(problem.state, Range(0, d), d + d_new),
      MeasurementTerm(problem.measurements, Range(0, problem.robot_dim), Range(d, d_new), d + d_new)};
  return GaussNewtonStep(Whiten(terms), linearization_point, layout);
}

// Proof of Theorem 6.2.2: C = [Σ^-1/2 (x̃ ⊟ μ); Σ̃v^-1/2 (z - h̃(x̃))], J = [Σ^-1/2; -Σ̃v^-1/2 H_t].
Gaussian EkfUpdateByGaussNewton(const EkfUpdateProblem& problem) {
  const Eigen::Index d = problem.layout.TangentSize();
  const std::vector<ResidualTerm> terms = {PriorTerm(problem.state, Range(0, d), d),
                                           MeasurementTerm(problem.measurements, Range(0, d), {}, d)};
  return GaussNewtonStep(Whiten(terms), problem.state.mean, problem.layout);
}

// Proofs of Theorems 6.2.3 / 6.2.5: variables ordered (x_{t+1}, rest, x_t) so
// that x_t (or its non-cloned part) is last; C = [Σ̄^-1/2 (x̃ ⊟ μ̄);
// Σw^-1/2 (x_{t+1} ⊟ g(x_t))].
Gaussian PropagationByMarginalization(const PropagationProblem& problem, bool keep_clone) {
  const PropagationSplit split = Split(problem);
  const Eigen::Index d_x = split.robot.TangentSize(), d_r = split.rest.TangentSize();
  const Eigen::Index d_k = keep_clone ? split.clone.TangentSize() : 0;
  const Eigen::Index cols = 2 * d_x + d_r;
  std::vector<Eigen::Index> prior_columns = Range(d_x + d_r, d_x);  // x_t
  const std::vector<Eigen::Index> rest_columns = Range(d_x, d_r);
  prior_columns.insert(prior_columns.end(), rest_columns.begin(), rest_columns.end());
  VIO_REQUIRE_SHAPE(problem.residual.J_to, d_x, d_x);
  VIO_REQUIRE_SHAPE(problem.residual.J_from, d_x, d_x);
  const ResidualTerm dynamics{problem.residual.r0,
                              PlaceColumns(problem.residual.J_to, Range(0, d_x), cols) +
                                  PlaceColumns(problem.residual.J_from, Range(d_x + d_r, d_x), cols),
                              problem.dynamics.Sigma_w};
  const std::vector<ResidualTerm> terms = {PriorTerm(problem.state, prior_columns, cols), dynamics};

  StateLayout kept_layout = split.robot;
  kept_layout.Append(split.rest);
  if (keep_clone) kept_layout.Append(split.clone);
  return MarginalizationStep(Whiten(terms), KeptPropagationPoint(problem, split, keep_clone), kept_layout,
                             {static_cast<int>(d_x - d_k)});
}

// Proof of Theorem 6.2.4: variables (x̃_t, f_{S_f}), C_M = [Σ^-1/2 (x̃ ⊟ μ);
// Σ̃v^-1/2 (z̃ ⊟ h̃(x̃, f))], J_K = [Σ^-1/2; -Σ̃v^-1/2 H_x], J_M = [O; -Σ̃v^-1/2 H_f].
Gaussian MsckfFeatureUpdateByMarginalization(const MsckfUpdateProblem& problem) {
  const Eigen::Index d = problem.layout.TangentSize();
  const Eigen::Index d_f = problem.feature_layout.TangentSize();
  std::vector<int> feature_dims;
  for (const StateBlock& block : problem.feature_layout.blocks()) feature_dims.push_back(block.tangent_size);
  const std::vector<ResidualTerm> terms = {
      PriorTerm(problem.state, Range(0, d), d + d_f),
      MeasurementTerm(problem.measurements, Range(0, d), Range(d, d_f), d + d_f)};
  return MarginalizationStep(Whiten(terms), problem.state.mean, problem.layout, feature_dims);
}

EquivalenceCheck CheckEkfAugmentation(const EkfAugmentationProblem& problem) {
  EquivalenceCheck check{"4.3.1", "EKF feature augmentation (Alg. 6) = 1 GN step on c_EKF,t,1", {}, {}, {}};
  check.filter = EkfAugmentFeatures(problem.state, problem.robot_dim, problem.new_feature_means, problem.L_x,
                                    problem.L_z, problem.measurements.Sigma_v);
  check.optimization = EkfAugmentationByGaussNewton(problem);
  StateLayout layout = problem.layout;
  layout.Append(problem.new_feature_layout);
  Eigen::VectorXd linearization_point(layout.AmbientSize());
  linearization_point << problem.state.mean, problem.new_feature_means;
  return Finish(check, layout, linearization_point);
}

EquivalenceCheck CheckEkfUpdate(const EkfUpdateProblem& problem) {
  EquivalenceCheck check{"4.3.2", "EKF feature update (Alg. 7) = 1 GN step on c_EKF,t,3", {}, {}, {}};
  check.filter = EkfUpdate(problem.state, problem.layout, problem.measurements);
  check.optimization = EkfUpdateByGaussNewton(problem);
  return Finish(check, problem.layout, problem.state.mean);
}

EquivalenceCheck CheckEkfPropagation(const PropagationProblem& problem) {
  EquivalenceCheck check{"4.3.3", "EKF propagation (Alg. 8) = marginalizing x_t from c_EKF,t,5", {}, {}, {}};
  check.filter = EkfPropagate(problem.state, problem.dynamics);
  check.optimization = PropagationByMarginalization(problem);
  return Finish(check, problem.layout, KeptPropagationPoint(problem, Split(problem), false));
}

EquivalenceCheck CheckMsckfFeatureUpdate(const MsckfUpdateProblem& problem) {
  EquivalenceCheck check{
      "4.3.4", "MSCKF feature update (Alg. 11) = marginalizing f from c_MSCKF,t,3", {}, {}, {}};
  check.filter = MsckfFeatureUpdate(problem.state, problem.layout, problem.measurements);
  check.optimization = MsckfFeatureUpdateByMarginalization(problem);
  return Finish(check, problem.layout, problem.state.mean);
}

EquivalenceCheck CheckMsckfPropagation(const PropagationProblem& problem) {
  EquivalenceCheck check{
      "4.3.5", "MSCKF propagation (Alg. 12) = marginalizing x_IMU from c_MSCKF,t,5", {}, {}, {}};
  check.filter = MsckfPropagate(problem.state, problem.dynamics);
  check.optimization = PropagationByMarginalization(problem);
  return Finish(check, problem.layout, KeptPropagationPoint(problem, Split(problem), false));
}

// Alg. 10 with ψ = the cloned blocks of x_IMU (Ψ = [I O]), then Alg. 12.
EquivalenceCheck CheckMsckfPoseAugmentation(const PropagationProblem& problem) {
  EquivalenceCheck check{"R4.3.2",
                         "MSCKF pose augmentation + propagation (Alg. 10+12) = marginalizing x_IMU but its "
                         "pose from c_MSCKF,t,5",
                         {},
                         {},
                         {}};
  const PropagationSplit split = Split(problem);
  VIO_REQUIRE_INPUT(split.clone.TangentSize() > 0);
  const Eigen::Index d = problem.layout.TangentSize(), d_k = split.clone.TangentSize();
  const Eigen::MatrixXd Psi = Eigen::MatrixXd::Identity(d_k, d);
  const Gaussian augmented =
      MsckfAugmentPose(problem.state, problem.state.mean.head(split.clone.AmbientSize()), Psi);
  check.filter = MsckfPropagate(augmented, problem.dynamics);
  check.optimization = PropagationByMarginalization(problem, /*keep_clone=*/true);
  StateLayout layout = problem.layout;
  layout.Append(split.clone);
  return Finish(check, layout, KeptPropagationPoint(problem, split, true));
}

std::vector<EquivalenceCheck> CheckAll(const EquivalenceProblems& problems) {
  std::vector<EquivalenceCheck> checks = {
      CheckEkfAugmentation(problems.ekf_augmentation), CheckEkfUpdate(problems.ekf_update),
      CheckEkfPropagation(problems.ekf_propagation), CheckMsckfFeatureUpdate(problems.msckf_update),
      CheckMsckfPropagation(problems.msckf_propagation)};
  if (problems.msckf_propagation.cloned_blocks > 0) {
    checks.push_back(CheckMsckfPoseAugmentation(problems.msckf_propagation));
  }
  return checks;
}

std::vector<EquivalenceCheck> NegativeControls(const EquivalenceProblems& problems) {
  const MsckfUpdateProblem& msckf = problems.msckf_update;
  EquivalenceCheck no_projection{"4.3.4", "control: MSCKF update without null-space projection", {}, {}, {}};
  no_projection.filter =
      EkfUpdate(msckf.state, msckf.layout,
                {msckf.measurements.innovation, msckf.measurements.H_x, {}, msckf.measurements.Sigma_v});
  no_projection.optimization = MsckfFeatureUpdateByMarginalization(msckf);

  const EkfUpdateProblem& ekf = problems.ekf_update;
  EquivalenceCheck perturbed{"4.3.2", "control: EKF update with H perturbed by 1e-5", {}, {}, {}};
  LinearizedMeasurements wrong = ekf.measurements;
  wrong.H_x *= 1.0 + 1e-5;
  perturbed.filter = EkfUpdate(ekf.state, ekf.layout, wrong);
  perturbed.optimization = EkfUpdateByGaussNewton(ekf);
  return {Finish(no_projection, msckf.layout, msckf.state.mean),
          Finish(perturbed, ekf.layout, ekf.state.mean)};
}

}  // namespace vio::marginalization
