#pragma once
// MarginalizationPrior: the linearized prior that marginalization leaves on
// the kept variables (design paper, Theorem 2.2.2), in square-root form.
//
// For kept parameter blocks x_1..x_n with manifolds M_i (nullptr = Euclidean)
// and linearization points x0_i copied at marginalization time:
//
//   delta_i = x_i ⊟ x0_i                 (Minus(x_i, x0_i); x_i - x0_i if Euclidean)
//   r(x)    = r0 + Jp * [delta_1; ...; delta_n]
//
// with Jp^T Jp = H* and Jp^T r0 = b*, the Schur-complemented normal equations.
// So 0.5 |r(x)|^2 is, up to a constant, the first-order marginal cost.
//
// Jacobians. Ceres asks for d r / d x_i in the AMBIENT space and multiplies it
// by PlusJacobian(x_i) itself. The tangent-space Jacobian we want is
//
//   d r(x_i ⊞ d) / d d |_{d=0} = Jp_i * T_i(x_i),   T_i = d Minus(x_i ⊞ d, x0_i) / d d |_{d=0}.
//
// We return the ambient Jacobian Jp_i * T_i * MinusJacobian(x_i): Ceres'
// manifold contract MinusJacobian(x) * PlusJacobian(x) = I makes the product
// with PlusJacobian exactly Jp_i * T_i. T_i is
//   * I for Euclidean blocks and whenever x_i == x0_i (exact),
//   * the manifold's closed form when it implements LocalCoordinatesJacobian,
//   * otherwise a central difference of Minus(Plus(x_i, d), x0_i) with step
//     kTangentStep (error ~1e-10), not the crude T_i ~= I approximation.
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <ceres/cost_function.h>
#include <ceres/manifold.h>

namespace vio::marginalization {

class MarginalizationPrior final : public ceres::CostFunction {
 public:
  /// One kept parameter block of the prior.
  struct Block {
    /// Manifold of the block (not owned; must outlive the prior), nullptr = Euclidean.
    const ceres::Manifold* manifold = nullptr;
    /// Linearization point x0 in ambient coordinates (AmbientSize values).
    std::vector<double> x0;
  };

  /// Central-difference step on the tangent space for manifolds without a
  /// closed-form LocalCoordinatesJacobian [tangent units].
  static constexpr double kTangentStep = 1e-5;

  /// r = residual_at_x0 + sqrt_information * [x_i ⊟ x0_i]. sqrt_information is
  /// rows x (sum of tangent sizes) with rows > 0. Throws std::invalid_argument
  /// on inconsistent sizes. Hand it to Ceres with `.release()`.
  static std::unique_ptr<MarginalizationPrior> Create(std::vector<Block> blocks,
                                                      Eigen::MatrixXd sqrt_information,
                                                      Eigen::VectorXd residual_at_x0);
  /// The same with Jp^T Jp already at hand (`information`, square, of the
  /// tangent size; the caller vouches that it is Jp^T Jp to round-off), which
  /// saves forming it (n^2 rows flops).
  static std::unique_ptr<MarginalizationPrior> Create(std::vector<Block> blocks,
                                                      Eigen::MatrixXd sqrt_information,
                                                      Eigen::VectorXd residual_at_x0,
                                                      Eigen::MatrixXd information);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  const std::vector<Block>& blocks() const { return blocks_; }
  /// Jp: rows x (sum of tangent sizes).
  const Eigen::MatrixXd& sqrt_information() const { return sqrt_information_; }
  /// r0: the residual at the linearization point.
  const Eigen::VectorXd& residual_at_x0() const { return residual_at_x0_; }
  /// The linearization point x0 of block i (AmbientSize values).
  const std::vector<double>& linearization_point(int i) const { return blocks_[i].x0; }
  /// First-estimate Jacobians: from now on the Jacobian is the one at x0 for
  /// every block, Jp_i on the tangent (T_i = I), wherever x is; the residual
  /// stays r0 + Jp (x ⊟ x0).
  void HoldJacobianAtLinearizationPoint() { jacobian_at_x0_ = true; }
  bool jacobian_at_linearization_point() const { return jacobian_at_x0_; }
  /// Jp^T Jp, computed once: the prior's information on the stacked deltas.
  const Eigen::MatrixXd& information() const { return information_; }
  /// Jp^T r0, computed once.
  const Eigen::VectorXd& information_vector() const { return information_vector_; }
  /// The prior linearized on the stacked tangent spaces at some parameters
  /// (Linearize), in the factored form its normal equations are assembled
  /// from block by block, without an n x n copy of information().
  struct TangentLinearization {
    /// Per block, T_i (see TangentJacobians); empty for the identity.
    std::vector<Eigen::MatrixXd> T;
    /// J^T r = T^T (Jp^T r0 + Jp^T Jp delta).
    Eigen::VectorXd g;
    /// 0.5 |r|^2.
    double cost = 0.0;
  };
  /// The prior at `parameters`; O(n^2), no Jp T formed. False when a block's
  /// local coordinates do not evaluate. Without `with_cost`, `at->cost` is 0 (one n^2 product
  /// fewer: a marginalization needs no cost).
  bool Linearize(double const* const* parameters, TangentLinearization* at, bool with_cost = true) const;
  /// Block (i, j) of J^T J at `at`: T_i^T information()_ij T_j.
  void TangentHessianBlock(const TangentLinearization& at, int i, int j, Eigen::MatrixXd* block) const;
  /// Column of block i in sqrt_information().
  int tangent_offset(int i) const { return tangent_offsets_[i]; }
  int tangent_size(int i) const { return tangent_sizes_[i]; }

 private:
  /// An empty `information` is computed as Jp^T Jp.
  MarginalizationPrior(std::vector<Block> blocks, Eigen::MatrixXd sqrt_information,
                       Eigen::VectorXd residual_at_x0, Eigen::MatrixXd information);

  /// The stacked deltas [x_i ⊟ x0_i] at `parameters`, and per block T_i (tangent x
  /// tangent, see above): the tangent Jacobian of r is Jp_i T_i, used by
  /// Linearize.
  bool TangentJacobians(double const* const* parameters, Eigen::VectorXd* delta,
                        std::vector<Eigen::MatrixXd>* T) const;
  /// delta_i = x_i ⊟ x0_i written into the tangent_size(i) values at `delta`.
  bool LocalCoordinates(int i, const double* x, double* delta) const;
  /// T_i(x) = d (x ⊞ d) ⊟ x0_i / d d at d = 0 (tangent x tangent).
  bool MinusTangentJacobian(int i, const double* x, Eigen::MatrixXd* T) const;
  /// Row-major rows x AmbientSize ambient Jacobian of r w.r.t. block i.
  bool AmbientJacobian(int i, const double* x, double* jacobian) const;

  std::vector<Block> blocks_;
  Eigen::MatrixXd sqrt_information_;
  Eigen::VectorXd residual_at_x0_;
  Eigen::MatrixXd information_;
  Eigen::VectorXd information_vector_;
  std::vector<int> tangent_offsets_;
  std::vector<int> tangent_sizes_;
  bool jacobian_at_x0_ = false;
};

}  // namespace vio::marginalization
