#pragma once
// BlockSystem's internals (block_system.h), shared by its two sources:
// block_system.cc (the structure found once, the landmark elimination, the
// back-substitution) and block_system_assembly.cc (evaluating the residuals
// and summing J^T J, J^T r and the priors' information). Included by those
// two files only.
#include <unordered_map>
#include <utility>
#include <vector>

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>
#include <ceres/manifold.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "vio/marginalization/block_system.h"
#include "vio/marginalization/marginalization_prior.h"
#include "vio/marginalization/tangent_cost_function.h"

namespace vio::marginalization {
namespace block_system_detail {

using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using ConstJacobian = Eigen::Map<const RowMajorMatrix>;

/// Where a parameter block's tangent space sits among the columns.
struct Columns {
  int offset = 0;
  int size = 0;
};

/// One parameter block of a residual block and where its Jacobian goes.
struct Slot {
  int dense = -1;       ///< dense block index, -1 for none
  int eliminated = -1;  ///< eliminated block index, -1 for none
  int coupling = -1;    ///< a dense block next to an eliminated one: its index in that block's `coupled`
  int tangent = 0;      ///< tangent size
  int ambient = 0;      ///< ambient (parameter block) size
  int jacobian = 0;     ///< offset of its (rows x tangent, row-major) Jacobian in the scratch buffer
  /// The block's PlusJacobian (ambient x tangent, row-major) in the solver's
  /// per-assembly cache; nullptr for a Euclidean block (the identity).
  const RowMajorMatrix* plus_jacobian = nullptr;
  bool variable() const { return dense >= 0 || eliminated >= 0; }
};

/// A view of `size` consecutive elements of one of Impl's arrays.
template <typename T>
struct Span {
  T* data = nullptr;
  size_t size = 0;
  T* begin() const { return data; }
  T* end() const { return data + size; }
  T& operator[](size_t k) const { return data[k]; }
};

/// A residual block and the columns it touches, found once per BlockSystem.
/// Its parameter blocks and slots live in the BlockSystem's shared arrays
/// (one allocation for all residuals, not two per residual).
struct Residual {
  ceres::ResidualBlockId id = nullptr;
  const ceres::CostFunction* cost = nullptr;
  const ceres::LossFunction* loss = nullptr;  ///< nullptr: none
  /// The same cost function when it gives tangent Jacobians itself.
  const TangentCostFunction* on_tangents = nullptr;
  int rows = 0;
  /// A marginalization prior without a loss: assembled from its information (AddPrior).
  const MarginalizationPrior* prior = nullptr;
  int first = 0;                ///< index of its first parameter block and slot in the shared arrays
  double* const* values = nullptr;  ///< its parameter blocks, in the residual's order
  Span<Slot> slots;                 ///< one per parameter block
  int eliminated = -1;  ///< the eliminated block it touches, -1 for none
};

/// One eliminated block: its part of the normal equations.
struct EliminatedBlock {
  Columns columns;
  std::vector<int> coupled;        ///< dense blocks its residuals touch, ascending columns
  Eigen::MatrixXd H;               ///< J_e^T J_e
  Eigen::VectorXd b;               ///< J_e^T r
  std::vector<Eigen::MatrixXd> W;  ///< J_d^T J_e per coupled dense block
  Eigen::MatrixXd H_inv;           ///< (pseudo-)inverse of H
};

/// A block of H's upper block triangle: rows of one dense block, columns of another.
struct Rectangle {
  int row = 0;
  int col = 0;
  int rows = 0;
  int cols = 0;
};

/// A Schur update -U U^T waiting to be applied to rows [first, first + rows).
struct PendingUpdate {
  int first = 0;
  int rows = 0;
  int cols = 0;        ///< U's columns
  size_t offset = 0;   ///< where U (rows x cols, column-major) starts in Impl::pending_u
};

}  // namespace block_system_detail

using block_system_detail::Columns;
using block_system_detail::ConstJacobian;
using block_system_detail::EliminatedBlock;
using block_system_detail::PendingUpdate;
using block_system_detail::Rectangle;
using block_system_detail::Residual;
using block_system_detail::RowMajorMatrix;
using block_system_detail::Slot;
using block_system_detail::Span;

// The normal equations of the dense columns (upper block triangle) and the
// per-block parts of the eliminated ones, summed in the layout's residual order.
struct BlockSystem::Impl {
  ceres::Problem* problem;
  BlockLayout layout;
  RankThreshold threshold;
  std::vector<Columns> dense;
  int dense_dim = 0;
  std::vector<EliminatedBlock> eliminated;
  /// Blocks a smaller layout left, their buffers kept for a larger one.
  std::vector<EliminatedBlock> spare_eliminated;
  std::vector<Residual> residuals;
  std::vector<double*> residual_values;  ///< every residual's parameter blocks, one after the other
  std::vector<Slot> residual_slots;      ///< every residual's slots, one after the other
  std::vector<double*> parameter_blocks;  ///< one residual's, while the structure is found
  /// The blocks of H an assembly of this layout can make non-zero (those of
  /// two dense blocks one residual or one eliminated block's Schur update
  /// couples, and the diagonal ones); found when H is first reused.
  std::vector<Rectangle> structure;
  bool structure_found = false;
  /// The blocks the last assembly may have written, when `written_known`: all
  /// of H's upper triangle outside them is zero, so Zero() clears only them.
  std::vector<Rectangle> written;
  bool written_known = false;
  // Buffers reused by every Reduce().
  Eigen::MatrixXd H;
  Eigen::VectorXd b;
  std::vector<double> r;
  std::vector<double> jacobians;
  std::vector<double> ambient_jacobians;  ///< what the cost function writes for blocks with a manifold
  std::vector<double*> jacobian_pointers;
  std::vector<std::pair<double*, int>> tangent_jacobians;  ///< one residual's (Jacobian, tangent size)
  /// PlusJacobian at the current values of every variable block with a
  /// manifold (dense, then eliminated blocks), refreshed once per assembly.
  std::vector<RowMajorMatrix> plus_jacobians;
  std::vector<std::pair<const ceres::Manifold*, const double*>> manifold_blocks;
  MarginalizationPrior::TangentLinearization prior_linearization;
  Eigen::MatrixXd prior_part;  ///< one block of a prior's J^T J
  // An eliminated block's Schur update (Eliminate), on buffers that only grow:
  // the sizes change from block to block, and a matrix resized for each would
  // reallocate every time.
  Eigen::LLT<Eigen::MatrixXd> factor;  ///< of its H_inv
  Eigen::VectorXd c;                   ///< factor.matrixU() b_e
  std::vector<double> u_buffer;        ///< its couplings stacked (StackCouplings), times the factor
  std::vector<double> ul_buffer;
  /// Contiguous Schur updates waiting to be applied (SubtractPendingUpdates),
  /// their U one after the other in `pending_u` (the first `pending_u_used`).
  std::vector<PendingUpdate> pending;
  std::vector<double> pending_u;
  size_t pending_u_used = 0;
  std::vector<double> stacked;  ///< a group's U side by side (SubtractPendingUpdates)

  // block_system.cc: structure, elimination, back-substitution, cost.
  Impl(ceres::Problem* p, BlockLayout l, const RankThreshold& t);
  void Build(BlockLayout l);
  std::pair<size_t, size_t> AddResidual(ceres::ResidualBlockId id, const std::unordered_map<const double*, Slot>& index);
  void Eliminate();
  void ResizeEliminated(size_t count);
  Eigen::Map<Eigen::MatrixXd> StackCouplings(const EliminatedBlock& block, int first, int rows);
  Eigen::Map<Eigen::MatrixXd> TimesFactor(Eigen::Map<Eigen::MatrixXd> U);
  void KeepPendingUpdate(int first, const Eigen::Map<Eigen::MatrixXd>& U);
  void SubtractPackedUpdate(const EliminatedBlock& block, const Eigen::Map<Eigen::MatrixXd>& U);
  void SubtractPendingUpdates();
  void EliminatePairwise(const EliminatedBlock& block);
  bool Reduce(double* cost);
  void BackSubstitute(const Eigen::VectorXd& dx_dense, Eigen::VectorXd* dx) const;
  bool Cost(double* cost);
  int CouplingBandwidth(const std::vector<int>& position) const;
  std::vector<std::pair<int, int>> CoupledSpans(const std::vector<bool>& counted) const;

  // block_system_assembly.cc: the normal equations at the current values (and
  // the blocks of H an assembly writes, cleared before the next).
  template <typename JacobianI, typename JacobianJ>
  void AddDensePair(const Slot& i, const Slot& j, const JacobianI& Ji, const JacobianJ& Jj);
  template <typename Product>
  void AddDenseProduct(const Slot& i, const Slot& j, const Product& product);
  bool AddGeneric(const Residual& residual, double* cost);
  bool EvaluateOnTangents(const Residual& residual, double* cost);
  bool RefreshPlusJacobians();
  static bool HasTangentsOf1Or3Or6(const Residual& residual);
  template <typename Residuals, typename WithJacobian>
  void Accumulate(const Residual& residual, const Residuals& res, const WithJacobian& with_jacobian);
  bool AddPrior(const Residual& residual, double* cost);
  void FindStructure();
  void Zero();
  bool AssembledFinite() const;
  bool Assemble(double* cost);
};

}  // namespace vio::marginalization
