#include "vio/marginalization/marginalization_prior.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "vio/marginalization/linear_algebra.h"
#include "vio/marginalization/local_coordinates_jacobian.h"

namespace vio::marginalization {
namespace {

using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

int TangentSizeOf(const MarginalizationPrior::Block& block) {
  return block.manifold != nullptr ? block.manifold->TangentSize()
                                   : static_cast<int>(block.x0.size());
}

void ValidateBlock(const MarginalizationPrior::Block& block, size_t index) {
  std::ostringstream problem;
  if (block.x0.empty()) {
    problem << "has an empty linearization point";
  } else if (block.manifold != nullptr &&
             block.manifold->AmbientSize() != static_cast<int>(block.x0.size())) {
    problem << "has " << block.x0.size() << " values but its manifold's ambient size is "
            << block.manifold->AmbientSize();
  } else if (!Eigen::Map<const Eigen::VectorXd>(block.x0.data(), block.x0.size()).allFinite()) {
    problem << "has a non-finite linearization point";
  }
  if (!problem.str().empty()) {
    throw std::invalid_argument("MarginalizationPrior: block " + std::to_string(index) + " " +
                                problem.str());
  }
}

void ValidatePrior(const std::vector<MarginalizationPrior::Block>& blocks,
                   const Eigen::MatrixXd& sqrt_information, const Eigen::VectorXd& residual_at_x0) {
  if (blocks.empty()) {
    throw std::invalid_argument("MarginalizationPrior: no parameter blocks");
  }
  int tangent_dim = 0;
  for (size_t i = 0; i < blocks.size(); ++i) {
    ValidateBlock(blocks[i], i);
    tangent_dim += TangentSizeOf(blocks[i]);
  }
  if (sqrt_information.rows() == 0 || sqrt_information.cols() != tangent_dim ||
      residual_at_x0.size() != sqrt_information.rows()) {
    std::ostringstream message;
    message << "MarginalizationPrior: sqrt_information is " << sqrt_information.rows() << "x"
            << sqrt_information.cols() << " and residual_at_x0 has " << residual_at_x0.size()
            << " rows; expected rows > 0, equal, and " << tangent_dim << " columns";
    throw std::invalid_argument(message.str());
  }
  if (!AllFinite(sqrt_information) || !AllFinite(residual_at_x0)) {
    throw std::invalid_argument("MarginalizationPrior: non-finite sqrt_information or residual");
  }
}

}  // namespace

std::unique_ptr<MarginalizationPrior> MarginalizationPrior::Create(std::vector<Block> blocks,
                                                                   Eigen::MatrixXd sqrt_information,
                                                                   Eigen::VectorXd residual_at_x0) {
  ValidatePrior(blocks, sqrt_information, residual_at_x0);
  return std::unique_ptr<MarginalizationPrior>(new MarginalizationPrior(
      std::move(blocks), std::move(sqrt_information), std::move(residual_at_x0), Eigen::MatrixXd()));
}

std::unique_ptr<MarginalizationPrior> MarginalizationPrior::Create(std::vector<Block> blocks,
                                                                   Eigen::MatrixXd sqrt_information,
                                                                   Eigen::VectorXd residual_at_x0,
                                                                   Eigen::MatrixXd information) {
  ValidatePrior(blocks, sqrt_information, residual_at_x0);
  if (information.rows() != sqrt_information.cols() || information.cols() != sqrt_information.cols() ||
      !AllFinite(information)) {
    std::ostringstream message;
    message << "MarginalizationPrior: information is " << information.rows() << "x" << information.cols()
            << "; expected a finite " << sqrt_information.cols() << "x" << sqrt_information.cols() << " matrix";
    throw std::invalid_argument(message.str());
  }
  return std::unique_ptr<MarginalizationPrior>(new MarginalizationPrior(
      std::move(blocks), std::move(sqrt_information), std::move(residual_at_x0), std::move(information)));
}

MarginalizationPrior::MarginalizationPrior(std::vector<Block> blocks,
                                           Eigen::MatrixXd sqrt_information,
                                           Eigen::VectorXd residual_at_x0,
                                           Eigen::MatrixXd information)
    : blocks_(std::move(blocks)),
      sqrt_information_(std::move(sqrt_information)),
      residual_at_x0_(std::move(residual_at_x0)),
      information_(std::move(information)) {
  set_num_residuals(static_cast<int>(residual_at_x0_.size()));
  int offset = 0;
  for (const Block& block : blocks_) {
    mutable_parameter_block_sizes()->push_back(static_cast<int32_t>(block.x0.size()));
    tangent_offsets_.push_back(offset);
    tangent_sizes_.push_back(TangentSizeOf(block));
    offset += tangent_sizes_.back();
  }
  if (information_.size() == 0) {
    information_ = Eigen::MatrixXd::Zero(offset, offset);
    information_.selfadjointView<Eigen::Lower>().rankUpdate(sqrt_information_.transpose());
    information_.triangularView<Eigen::StrictlyUpper>() = information_.transpose();
  }
  information_vector_ = sqrt_information_.transpose() * residual_at_x0_;
}

bool MarginalizationPrior::TangentJacobians(double const* const* parameters, Eigen::VectorXd* delta,
                                            std::vector<Eigen::MatrixXd>* T) const {
  delta->resize(sqrt_information_.cols());
  T->resize(blocks_.size());
  for (size_t i = 0; i < blocks_.size(); ++i) {
    const int block = static_cast<int>(i);
    if (!LocalCoordinates(block, parameters[i], delta->data() + tangent_offsets_[i]) ||
        !MinusTangentJacobian(block, parameters[i], &(*T)[i])) {
      return false;
    }
  }
  return true;
}

bool MarginalizationPrior::Linearize(double const* const* parameters, TangentLinearization* at,
                                     bool with_cost) const {
  Eigen::VectorXd delta;
  if (!TangentJacobians(parameters, &delta, &at->T)) return false;
  if (delta.isZero(0.0)) {
    // At x0 (a prior's first solve): the products with delta are exact zeros, and adding them
    // changes only a -0 into +0, as adding 0.0 does.
    at->cost = with_cost ? 0.5 * residual_at_x0_.squaredNorm() : 0.0;
    at->g = (information_vector_.array() + 0.0).matrix();
  } else {
    at->cost = with_cost ? 0.5 * (residual_at_x0_ + sqrt_information_ * delta).squaredNorm() : 0.0;
    at->g = information_vector_ + information_ * delta;
  }
  for (size_t i = 0; i < blocks_.size(); ++i) {
    Eigen::MatrixXd& T = at->T[i];
    if (T.isIdentity(0.0)) {
      T.resize(0, 0);
    } else {
      auto g = at->g.segment(tangent_offsets_[i], tangent_sizes_[i]);
      g = T.transpose() * g;
    }
  }
  return true;
}

void MarginalizationPrior::TangentHessianBlock(const TangentLinearization& at, int i, int j,
                                               Eigen::MatrixXd* block) const {
  const auto information =
      information_.block(tangent_offsets_[i], tangent_offsets_[j], tangent_sizes_[i], tangent_sizes_[j]);
  const Eigen::MatrixXd& T_i = at.T[static_cast<size_t>(i)];
  const Eigen::MatrixXd& T_j = at.T[static_cast<size_t>(j)];
  if (T_i.size() == 0 && T_j.size() == 0) {
    *block = information;
  } else if (T_i.size() == 0) {
    block->noalias() = information * T_j;
  } else if (T_j.size() == 0) {
    block->noalias() = T_i.transpose() * information;
  } else if (T_i.rows() == 6 && T_i.cols() == 6 && T_j.rows() == 6 && T_j.cols() == 6) {
    // Two poses (the common pair): fixed-size products, no temporary on the heap.
    using Matrix6 = Eigen::Matrix<double, 6, 6>;
    const Matrix6 information_T_j = information * Eigen::Map<const Matrix6>(T_j.data());
    block->noalias() = Eigen::Map<const Matrix6>(T_i.data()).transpose() * information_T_j;
  } else {
    block->noalias() = T_i.transpose() * (information * T_j);
  }
}

bool MarginalizationPrior::Evaluate(double const* const* parameters, double* residuals,
                                    double** jacobians) const {
  Eigen::VectorXd delta(sqrt_information_.cols());
  for (size_t i = 0; i < blocks_.size(); ++i) {
    if (!LocalCoordinates(static_cast<int>(i), parameters[i], delta.data() + tangent_offsets_[i])) {
      return false;
    }
  }
  Eigen::Map<Eigen::VectorXd>(residuals, num_residuals()) =
      residual_at_x0_ + sqrt_information_ * delta;
  if (jacobians == nullptr) {
    return true;
  }
  for (size_t i = 0; i < blocks_.size(); ++i) {
    if (jacobians[i] != nullptr &&
        !AmbientJacobian(static_cast<int>(i), parameters[i], jacobians[i])) {
      return false;
    }
  }
  return true;
}

bool MarginalizationPrior::LocalCoordinates(int i, const double* x, double* delta) const {
  const Block& block = blocks_[i];
  if (block.manifold != nullptr) {
    return block.manifold->Minus(x, block.x0.data(), delta);
  }
  const int size = static_cast<int>(block.x0.size());
  Eigen::Map<Eigen::VectorXd>(delta, size) =
      Eigen::Map<const Eigen::VectorXd>(x, size) -
      Eigen::Map<const Eigen::VectorXd>(block.x0.data(), size);
  return true;
}

bool MarginalizationPrior::MinusTangentJacobian(int i, const double* x, Eigen::MatrixXd* T) const {
  const Block& block = blocks_[i];
  const int n = tangent_sizes_[i];
  if (block.manifold == nullptr || jacobian_at_x0_ || std::equal(block.x0.begin(), block.x0.end(), x)) {
    *T = Eigen::MatrixXd::Identity(n, n);
    return true;
  }
  if (const auto* exact = dynamic_cast<const LocalCoordinatesJacobian*>(block.manifold)) {
    RowMajorMatrix T_row_major(n, n);
    if (!exact->MinusTangentJacobian(x, block.x0.data(), T_row_major.data())) {
      return false;
    }
    *T = T_row_major;
    return true;
  }
  T->resize(n, n);
  std::vector<double> x_moved(block.x0.size());
  Eigen::VectorXd step = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd forward(n);
  Eigen::VectorXd backward(n);
  for (int k = 0; k < n; ++k) {
    step(k) = kTangentStep;
    bool ok = block.manifold->Plus(x, step.data(), x_moved.data()) &&
              block.manifold->Minus(x_moved.data(), block.x0.data(), forward.data());
    step(k) = -kTangentStep;
    ok = ok && block.manifold->Plus(x, step.data(), x_moved.data()) &&
         block.manifold->Minus(x_moved.data(), block.x0.data(), backward.data());
    step(k) = 0.0;
    if (!ok) {
      return false;
    }
    T->col(k) = (forward - backward) / (2.0 * kTangentStep);
  }
  return true;
}

bool MarginalizationPrior::AmbientJacobian(int i, const double* x, double* jacobian) const {
  const Block& block = blocks_[i];
  const int ambient = static_cast<int>(block.x0.size());
  const int tangent = tangent_sizes_[i];
  Eigen::Map<RowMajorMatrix> d_res_d_x(jacobian, num_residuals(), ambient);
  const auto Jp_block = sqrt_information_.middleCols(tangent_offsets_[i], tangent);
  if (block.manifold == nullptr) {
    d_res_d_x = Jp_block;
    return true;
  }
  Eigen::MatrixXd d_minus_d_tangent;
  RowMajorMatrix d_tangent_d_x(tangent, ambient);
  if (!MinusTangentJacobian(i, x, &d_minus_d_tangent) ||
      !block.manifold->MinusJacobian(x, d_tangent_d_x.data())) {
    return false;
  }
  d_res_d_x = Jp_block * d_minus_d_tangent * d_tangent_d_x;
  return true;
}

}  // namespace vio::marginalization
