#include "vio/marginalization/block_system.h"

#include <algorithm>
#include <cmath>
#include <tuple>
#include <unordered_map>
#include <utility>

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>
#include <ceres/manifold.h>
#include <glog/logging.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "vio/marginalization/marginalization_prior.h"
#include "vio/marginalization/tangent_cost_function.h"

namespace vio::marginalization {
namespace {


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

/// A residual block and the columns it touches, found once per solve.
struct Residual {
  ceres::ResidualBlockId id = nullptr;
  const ceres::CostFunction* cost = nullptr;
  const ceres::LossFunction* loss = nullptr;  ///< nullptr: none
  /// The same cost function when it gives tangent Jacobians itself.
  const TangentCostFunction* on_tangents = nullptr;
  int rows = 0;
  /// A marginalization prior on dense blocks only: assembled from its information.
  const MarginalizationPrior* prior = nullptr;
  std::vector<double*> values;  ///< its parameter blocks, in the residual's order
  std::vector<Slot> slots;
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
  Eigen::MatrixXd U;               ///< its Schur update is -U U^T on contiguous coupled columns
};

/// A Schur update -U U^T waiting to be applied to rows [first, first + rows).
struct PendingUpdate {
  int first = 0;
  int rows = 0;
  int block = 0;  ///< the eliminated block holding U
};

/// Ceres' Corrector on one row-major Jacobian: J <- sqrt_rho1 (J - alpha_sq_norm r (r^T J)).
template <int Rows, typename Residuals>
void CorrectJacobian(const Residuals& res, double alpha_sq_norm, double sqrt_rho1, int tangent, double* jacobian) {
  Eigen::Map<Eigen::Matrix<double, Rows, Eigen::Dynamic, Eigen::RowMajor>> J(jacobian, res.size(), tangent);
  if (alpha_sq_norm != 0.0) J -= alpha_sq_norm * res * (res.transpose() * J);
  J *= sqrt_rho1;
}

/// The robust loss applied as Ceres applies it (its Corrector, after Triggs et
/// al.): J <- sqrt(rho') (J - alpha r r^T J / |r|^2) for every (Jacobian,
/// tangent size) in `jacobians`, then r <- sqrt(rho') r / (1 - alpha); returns
/// the cost 0.5 rho(|r|^2).
double ApplyLoss(const ceres::LossFunction& loss, Eigen::Map<Eigen::VectorXd> res,
                 const std::vector<std::pair<double*, int>>& jacobians) {
  const double squared_norm = res.squaredNorm();
  double rho[3];
  loss.Evaluate(squared_norm, rho);
  const double sqrt_rho1 = std::sqrt(rho[1]);
  double residual_scaling = sqrt_rho1;
  double alpha_sq_norm = 0.0;
  if (squared_norm != 0.0 && rho[2] > 0.0) {
    const double alpha = 1.0 - std::sqrt(1.0 + 2.0 * squared_norm * rho[2] / rho[1]);
    residual_scaling = sqrt_rho1 / (1.0 - alpha);
    alpha_sq_norm = alpha / squared_norm;
  }
  for (const auto& [jacobian, tangent] : jacobians) {
    if (res.size() == 3) {  // stereo residuals, on fixed-size products
      CorrectJacobian<3>(Eigen::Map<const Eigen::Vector3d>(res.data()), alpha_sq_norm, sqrt_rho1, tangent, jacobian);
    } else {
      CorrectJacobian<Eigen::Dynamic>(res, alpha_sq_norm, sqrt_rho1, tangent, jacobian);
    }
  }
  res *= residual_scaling;
  return 0.5 * rho[0];
}

}  // namespace

// The normal equations of the dense columns (upper block triangle) and the
// per-block parts of the eliminated ones, summed in the layout's residual order.
struct BlockSystem::Impl {
  ceres::Problem* problem;
  BlockLayout layout;
  RankThreshold threshold;
  std::vector<Columns> dense;
  int dense_dim = 0;
  std::vector<EliminatedBlock> eliminated;
  std::vector<Residual> residuals;
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
  Eigen::MatrixXd prior_H;
  Eigen::VectorXd prior_g;
  Eigen::MatrixXd U;
  Eigen::MatrixXd UUt;
  /// Contiguous Schur updates waiting to be applied (SubtractPendingUpdates).
  std::vector<PendingUpdate> pending;
  Eigen::MatrixXd stacked;
  Eigen::MatrixXd UL;

  Impl(ceres::Problem* p, BlockLayout l, const RankThreshold& t) : problem(p), layout(std::move(l)), threshold(t) {
    // A lookup from variable block to its slot fields only: no order depends on the addresses.
    std::unordered_map<const double*, Slot> index;
    index.reserve(layout.dense.size() + layout.eliminated.size());
    for (size_t k = 0; k < layout.dense.size(); ++k) {
      dense.push_back({dense_dim, problem->ParameterBlockTangentSize(layout.dense[k])});
      dense_dim += dense.back().size;
      index[layout.dense[k]].dense = static_cast<int>(k);
    }
    int col = dense_dim;
    eliminated.resize(layout.eliminated.size());
    for (size_t k = 0; k < layout.eliminated.size(); ++k) {
      eliminated[k].columns = {col, problem->ParameterBlockTangentSize(layout.eliminated[k])};
      col += eliminated[k].columns.size;
      index[layout.eliminated[k]].eliminated = static_cast<int>(k);
    }
    for (const std::vector<double*>* blocks : {&layout.dense, &layout.eliminated}) {
      for (const double* block : *blocks) {
        Slot& slot = index[block];
        slot.tangent = slot.dense >= 0 ? dense[slot.dense].size : eliminated[slot.eliminated].columns.size;
        slot.ambient = problem->ParameterBlockSize(block);
        if (const ceres::Manifold* manifold = problem->GetManifold(block)) manifold_blocks.emplace_back(manifold, block);
      }
    }
    plus_jacobians.resize(manifold_blocks.size());
    for (size_t k = 0; k < manifold_blocks.size(); ++k) index[manifold_blocks[k].second].plus_jacobian = &plus_jacobians[k];
    size_t scratch = 0;
    size_t ambient_scratch = 0;
    residuals.reserve(layout.residuals.size());
    for (ceres::ResidualBlockId id : layout.residuals) {
      const auto [tangent_size, ambient_size] = AddResidual(id, index);
      scratch = std::max(scratch, tangent_size);
      ambient_scratch = std::max(ambient_scratch, ambient_size);
    }
    ambient_jacobians.resize(ambient_scratch);
    for (EliminatedBlock& block : eliminated) {
      std::sort(block.coupled.begin(), block.coupled.end());
      block.coupled.erase(std::unique(block.coupled.begin(), block.coupled.end()), block.coupled.end());
      block.W.resize(block.coupled.size());
    }
    for (Residual& residual : residuals) {
      if (residual.eliminated < 0) continue;
      const std::vector<int>& coupled = eliminated[residual.eliminated].coupled;
      for (Slot& slot : residual.slots) {
        if (slot.dense < 0) continue;
        slot.coupling = static_cast<int>(std::lower_bound(coupled.begin(), coupled.end(), slot.dense) - coupled.begin());
      }
    }
    jacobians.resize(scratch);
  }
  // The residual's slots; returns the scratch its tangent Jacobians and its
  // ambient ones (blocks with a manifold) need.
  std::pair<size_t, size_t> AddResidual(ceres::ResidualBlockId id, const std::unordered_map<const double*, Slot>& index) {
    Residual& residual = residuals.emplace_back();
    residual.id = id;
    const ceres::CostFunction* cost = problem->GetCostFunctionForResidualBlock(id);
    residual.cost = cost;
    residual.loss = problem->GetLossFunctionForResidualBlock(id);
    residual.on_tangents = dynamic_cast<const TangentCostFunction*>(cost);
    residual.rows = cost->num_residuals();
    problem->GetParameterBlocksForResidualBlock(id, &residual.values);
    int jacobian = 0;
    int ambient = 0;
    for (const double* value : residual.values) {
      // A block outside the layout is held constant: no Jacobian, no columns.
      const auto it = index.find(value);
      Slot slot = it != index.end() ? it->second : Slot{};
      if (slot.eliminated >= 0) {
        CHECK(residual.eliminated < 0 || residual.eliminated == slot.eliminated)
            << "a residual couples two eliminated blocks";
        residual.eliminated = slot.eliminated;
      }
      slot.jacobian = jacobian;
      if (slot.variable()) jacobian += residual.rows * slot.tangent;
      if (slot.variable() && slot.plus_jacobian != nullptr) ambient = std::max(ambient, residual.rows * slot.ambient);
      residual.slots.push_back(slot);
    }
    if (residual.eliminated >= 0) {
      for (const Slot& slot : residual.slots) {
        if (slot.dense >= 0) eliminated[residual.eliminated].coupled.push_back(slot.dense);
      }
    }
    if (residual.loss == nullptr) {  // with a loss, as any other residual
      residual.prior = dynamic_cast<const MarginalizationPrior*>(cost);
    }
    r.resize(std::max(r.size(), static_cast<size_t>(residual.rows)));
    jacobian_pointers.resize(std::max(jacobian_pointers.size(), residual.values.size()));
    if (residual.prior != nullptr) return {0, 0};  // from its information (AddPrior): no Jacobian scratch
    return {static_cast<size_t>(jacobian), static_cast<size_t>(ambient) * residual.values.size()};
  }

  // Only H's upper triangle is read (the chain and dense solves, the rank
  // updates); the diagonal blocks are written whole, so they are zeroed whole.
  void Zero() {
    H.resize(dense_dim, dense_dim);
    H.triangularView<Eigen::Upper>().setZero();
    for (const Columns& c : dense) H.block(c.offset, c.offset, c.size, c.size).setZero();
    b.setZero(dense_dim);
    for (EliminatedBlock& block : eliminated) {
      const int n = block.columns.size;
      block.H.setZero(n, n);
      block.b.setZero(n);
      for (size_t k = 0; k < block.coupled.size(); ++k) block.W[k].setZero(dense[block.coupled[k]].size, n);
    }
  }

  // J_i^T J_j into the upper block triangle of H.
  template <typename JacobianI, typename JacobianJ>
  void AddDensePair(const Slot& i, const Slot& j, const JacobianI& Ji, const JacobianJ& Jj) {
    const Columns& a = dense[i.dense];
    const Columns& c = dense[j.dense];
    if (a.offset <= c.offset) {
      H.block(a.offset, c.offset, a.size, c.size).noalias() += Ji.transpose() * Jj;
    } else {
      H.block(c.offset, a.offset, c.size, a.size).noalias() += Jj.transpose() * Ji;
    }
  }

  // A product for blocks (i, j) into the upper block triangle of H.
  template <typename Product>
  void AddDenseProduct(const Slot& i, const Slot& j, const Product& product) {
    const Columns& a = dense[i.dense];
    const Columns& c = dense[j.dense];
    if (a.offset <= c.offset) {
      H.block(a.offset, c.offset, a.size, c.size) += product;
    } else {
      H.block(c.offset, a.offset, c.size, a.size) += product.transpose();
    }
  }

  bool AddGeneric(const Residual& residual, double* cost) {
    if (!EvaluateOnTangents(residual, cost)) return false;
    // A stereo residual (3 rows on 6- and 3-dimensional tangents) takes
    // fixed-size products; every other shape the dynamic ones.
    if (residual.rows == 3 && HasTangentsOf3Or6(residual)) {
      Accumulate(residual, Eigen::Map<const Eigen::Vector3d>(r.data()), [&](const Slot& slot, const auto& use) {
        const double* data = jacobians.data() + slot.jacobian;
        if (slot.tangent == 6) {
          use(Eigen::Map<const Eigen::Matrix<double, 3, 6, Eigen::RowMajor>>(data));
        } else {
          use(Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(data));
        }
      });
      return true;
    }
    Accumulate(residual, Eigen::Map<const Eigen::VectorXd>(r.data(), residual.rows),
               [&](const Slot& slot, const auto& use) {
                 use(ConstJacobian(jacobians.data() + slot.jacobian, residual.rows, slot.tangent));
               });
    return true;
  }

  // What Problem::EvaluateResidualBlock(apply_loss_function = true) gives,
  // without its per-call bookkeeping: the cost 0.5 rho(|r|^2), the residual
  // and the tangent Jacobians (from a TangentCostFunction directly, else
  // ambient ones times the assembly's cached PlusJacobian), corrected for the loss
  // (ApplyLoss). False when the cost function fails or gives a non-finite value.
  bool EvaluateOnTangents(const Residual& residual, double* cost) {
    const int rows = residual.rows;
    const bool on_tangents = residual.on_tangents != nullptr;  // no ambient round trip
    for (size_t k = 0, ambient = 0; k < residual.slots.size(); ++k) {
      const Slot& slot = residual.slots[k];
      if (!slot.variable()) {
        jacobian_pointers[k] = nullptr;
      } else if (slot.plus_jacobian == nullptr || on_tangents) {
        jacobian_pointers[k] = jacobians.data() + slot.jacobian;
      } else {
        jacobian_pointers[k] = ambient_jacobians.data() + ambient;
        ambient += static_cast<size_t>(rows * slot.ambient);
      }
    }
    const bool evaluated =
        on_tangents ? residual.on_tangents->EvaluateOnTangents(residual.values.data(), r.data(), jacobian_pointers.data())
                    : residual.cost->Evaluate(residual.values.data(), r.data(), jacobian_pointers.data());
    Eigen::Map<Eigen::VectorXd> res(r.data(), rows);
    if (!evaluated || !res.allFinite()) return false;
    tangent_jacobians.clear();
    for (size_t k = 0; k < residual.slots.size(); ++k) {
      const Slot& slot = residual.slots[k];
      if (!slot.variable()) continue;
      Eigen::Map<RowMajorMatrix> tangent(jacobians.data() + slot.jacobian, rows, slot.tangent);
      if (slot.plus_jacobian != nullptr && !on_tangents) {
        tangent.noalias() = Eigen::Map<const RowMajorMatrix>(jacobian_pointers[k], rows, slot.ambient) * *slot.plus_jacobian;
      }
      if (!tangent.allFinite()) return false;
      tangent_jacobians.emplace_back(tangent.data(), slot.tangent);
    }
    *cost = residual.loss == nullptr ? 0.5 * res.squaredNorm() : ApplyLoss(*residual.loss, res, tangent_jacobians);
    return std::isfinite(*cost);
  }

  // PlusJacobian of every variable block with a manifold at the current values.
  bool RefreshPlusJacobians() {
    for (size_t k = 0; k < manifold_blocks.size(); ++k) {
      const auto& [manifold, values] = manifold_blocks[k];
      plus_jacobians[k].resize(manifold->AmbientSize(), manifold->TangentSize());
      if (!manifold->PlusJacobian(values, plus_jacobians[k].data())) return false;
    }
    return true;
  }

  static bool HasTangentsOf3Or6(const Residual& residual) {
    for (const Slot& slot : residual.slots) {
      if (slot.variable() && slot.tangent != 3 && slot.tangent != 6) return false;
    }
    return true;
  }

  // One residual's J^T J and J^T r into H and b (dense blocks) and into the
  // eliminated blocks' H, b and couplings W; with_jacobian(slot, use) calls
  // use with the slot's Jacobian.
  template <typename Residuals, typename WithJacobian>
  void Accumulate(const Residual& residual, const Residuals& res, const WithJacobian& with_jacobian) {
    for (size_t p = 0; p < residual.slots.size(); ++p) {
      const Slot& i = residual.slots[p];
      if (!i.variable()) continue;
      with_jacobian(i, [&](const auto& Ji) {
        if (i.dense >= 0) {
          b.segment(dense[i.dense].offset, i.tangent).noalias() += Ji.transpose() * res;
          for (size_t q = p; q < residual.slots.size(); ++q) {
            const Slot& j = residual.slots[q];
            if (j.dense >= 0) with_jacobian(j, [&](const auto& Jj) { AddDensePair(i, j, Ji, Jj); });
          }
          return;
        }
        EliminatedBlock& block = eliminated[i.eliminated];
        block.b.noalias() += Ji.transpose() * res;
        block.H.noalias() += Ji.transpose() * Ji;
        for (const Slot& j : residual.slots) {
          if (j.dense >= 0) {
            with_jacobian(j, [&](const auto& Jj) { block.W[j.coupling].noalias() += Jj.transpose() * Ji; });
          }
        }
      });
    }
  }

  // A prior r = r0 + Jp delta, assembled from its information (see
  // MarginalizationPrior::TangentNormalEquations) without forming Jp T: its
  // blocks' parts go where a residual's J_i^T J_j would (H, b, or the
  // eliminated block's H, b and couplings W).
  bool AddPrior(const Residual& residual, double* cost) {
    const MarginalizationPrior& prior = *residual.prior;
    if (!prior.TangentNormalEquations(residual.values.data(), &prior_H, &prior_g, cost)) return false;
    const int n = static_cast<int>(residual.slots.size());
    const auto part = [&](int i, int j) {
      return prior_H.block(prior.tangent_offset(i), prior.tangent_offset(j), residual.slots[i].tangent,
                           residual.slots[j].tangent);
    };
    for (int i = 0; i < n; ++i) {
      const Slot& si = residual.slots[i];
      const auto g = prior_g.segment(prior.tangent_offset(i), si.tangent);
      if (si.eliminated >= 0) {
        EliminatedBlock& block = eliminated[si.eliminated];
        block.b += g;
        block.H += part(i, i);
        for (int j = 0; j < n; ++j) {
          if (residual.slots[j].dense >= 0) block.W[residual.slots[j].coupling] += part(j, i);
        }
      }
      if (si.dense < 0) continue;
      b.segment(dense[si.dense].offset, si.tangent) += g;
      for (int j = i; j < n; ++j) {
        if (residual.slots[j].dense >= 0) AddDenseProduct(si, residual.slots[j], part(i, j));
      }
    }
    return true;
  }

  bool Assemble(double* cost) {
    if (!RefreshPlusJacobians()) return false;
    Zero();
    *cost = 0;
    for (const Residual& residual : residuals) {
      double c = 0;
      if (!(residual.prior != nullptr ? AddPrior(residual, &c) : AddGeneric(residual, &c))) return false;
      *cost += c;
    }
    return true;
  }

  /// Schur complement of the eliminated blocks into (H, b), block by block:
  /// with H_inv = S S^T, U = [W_1; ...; W_m] S, the update is one rank-n
  /// update H -= U U^T over the coupled columns (in place over their span,
  /// with zero rows in its gaps, grouped by row range: SubtractPendingUpdates;
  /// pair by pair when the span is mostly gaps) and b -= U S^T b_e.
  void Eliminate() {
    pending.clear();
    for (size_t k = 0; k < eliminated.size(); ++k) {
      EliminatedBlock& block = eliminated[k];
      block.H_inv = PseudoInverse(block.H, threshold);
      const Eigen::LLT<Eigen::MatrixXd> factor(block.H_inv);
      if (factor.info() != Eigen::Success) {  // H_inv singular (rank-truncated): no square root
        EliminatePairwise(block);
        continue;
      }
      if (block.coupled.empty()) continue;
      // U over the span of its coupled columns, zero rows in the gaps (a
      // track that skipped a frame): one contiguous update unless the span is
      // mostly gaps.
      const int first = dense[block.coupled.front()].offset;
      const int span = dense[block.coupled.back()].offset + dense[block.coupled.back()].size - first;
      int rows = 0;
      for (const int d : block.coupled) rows += dense[d].size;
      const bool contiguous = span <= 2 * rows;
      StackCouplings(block, contiguous ? first : -1, contiguous ? span : rows);
      if (U.cols() == 3) {  // a landmark: the 3x3 factor on fixed-size, coefficient by coefficient
        const Eigen::Matrix3d L = factor.matrixL();
        UL.noalias() = U.lazyProduct(L);
        U.swap(UL);
      } else {
        U = U * factor.matrixL();
      }
      const Eigen::VectorXd c = factor.matrixU() * block.b;
      if (contiguous) {
        b.segment(first, span).noalias() -= U * c;
        block.U = U;
        pending.push_back({first, span, static_cast<int>(k)});
      } else {
        SubtractPackedUpdate(block, c);
      }
    }
    SubtractPendingUpdates();
  }

  // U = the block's couplings W stacked: at their columns' offsets from
  // `first` over `rows` rows (zero rows in the gaps), or packed one after the
  // other when `first` is -1.
  void StackCouplings(const EliminatedBlock& block, int first, int rows) {
    if (first >= 0) {
      U.setZero(rows, block.columns.size);
    } else {
      U.resize(rows, block.columns.size);
    }
    for (size_t p = 0, packed = 0; p < block.coupled.size(); packed += block.W[p].rows(), ++p) {
      const Eigen::Index row = first >= 0 ? dense[block.coupled[p]].offset - first : static_cast<Eigen::Index>(packed);
      U.middleRows(row, block.W[p].rows()) = block.W[p];
    }
  }

  // b -= U c and H -= U U^T block pair by block pair, U packed (StackCouplings).
  void SubtractPackedUpdate(const EliminatedBlock& block, const Eigen::VectorXd& c) {
    const Eigen::Index rows = U.rows();
    for (size_t p = 0, rp = 0; p < block.coupled.size(); rp += dense[block.coupled[p]].size, ++p) {
      const Columns& a = dense[block.coupled[p]];
      b.segment(a.offset, a.size).noalias() -= U.middleRows(rp, a.size) * c;
    }
    UUt.setZero(rows, rows);
    UUt.selfadjointView<Eigen::Upper>().rankUpdate(U);
    for (size_t p = 0, rp = 0; p < block.coupled.size(); rp += dense[block.coupled[p]].size, ++p) {
      const Columns& a = dense[block.coupled[p]];
      for (size_t q = p, rq = rp; q < block.coupled.size(); rq += dense[block.coupled[q]].size, ++q) {
        const Columns& c2 = dense[block.coupled[q]];
        H.block(a.offset, c2.offset, a.size, c2.size) -= UUt.block(rp, rq, a.size, c2.size);
      }
    }
  }

  // The contiguous updates H -= U U^T grouped by the rows they touch: one
  // rank update with all the group's columns side by side (landmarks seen by
  // the same states share the rows) instead of one three-column update each,
  // which the blocked product handles at a fraction of its speed.
  void SubtractPendingUpdates() {
    // Grouped by row range; within a group in block order, so the order of
    // the updates depends on the layout only.
    std::stable_sort(pending.begin(), pending.end(), [](const PendingUpdate& a, const PendingUpdate& b) {
      return std::tie(a.first, a.rows) < std::tie(b.first, b.rows);
    });
    for (size_t begin = 0, end = 0; begin < pending.size(); begin = end) {
      const PendingUpdate& group = pending[begin];
      Eigen::Index columns = 0;
      for (end = begin; end < pending.size() && pending[end].first == group.first && pending[end].rows == group.rows;
           ++end) {
        columns += eliminated[pending[end].block].U.cols();
      }
      stacked.resize(group.rows, columns);
      columns = 0;
      for (size_t k = begin; k < end; ++k) {
        const Eigen::MatrixXd& u = eliminated[pending[k].block].U;
        stacked.middleCols(columns, u.cols()) = u;
        columns += u.cols();
      }
      H.block(group.first, group.first, group.rows, group.rows).selfadjointView<Eigen::Upper>().rankUpdate(stacked, -1.0);
    }
  }

  // The Schur update of one block through its pseudo-inverse, pair by pair.
  void EliminatePairwise(const EliminatedBlock& block) {
    Eigen::MatrixXd WH_inv;
    for (size_t p = 0; p < block.coupled.size(); ++p) {
      const Columns& a = dense[block.coupled[p]];
      WH_inv.noalias() = block.W[p] * block.H_inv;
      b.segment(a.offset, a.size).noalias() -= WH_inv * block.b;
      for (size_t q = p; q < block.coupled.size(); ++q) {
        const Columns& c = dense[block.coupled[q]];
        H.block(a.offset, c.offset, a.size, c.size).noalias() -= WH_inv * block.W[q].transpose();
      }
    }
  }

  // The reduced system (H upper triangle, b) at the current values; false
  // when the layout is empty or evaluation fails.
  bool Reduce(double* cost) {
    if (residuals.empty() || (layout.dense.empty() && layout.eliminated.empty())) return false;
    if (!Assemble(cost)) return false;
    Eliminate();
    return true;
  }

  void BackSubstitute(const Eigen::VectorXd& dx_dense, Eigen::VectorXd* dx) const {
    dx->resize(eliminated.empty() ? dense_dim : eliminated.back().columns.offset + eliminated.back().columns.size);
    dx->head(dense_dim) = dx_dense;
    Eigen::VectorXd rhs;
    for (const EliminatedBlock& block : eliminated) {
      rhs = block.b;
      for (size_t p = 0; p < block.coupled.size(); ++p) {
        const Columns& a = dense[block.coupled[p]];
        rhs.noalias() += block.W[p].transpose() * dx_dense.segment(a.offset, a.size);
      }
      dx->segment(block.columns.offset, block.columns.size).noalias() = -block.H_inv * rhs;
    }
  }

  // As Ceres evaluates a residual block's cost (0.5 rho(|r|^2), invalid when
  // not finite) without its per-call bookkeeping.
  bool Cost(double* cost) {
    *cost = 0;
    for (const Residual& residual : residuals) {
      if (!residual.cost->Evaluate(residual.values.data(), r.data(), nullptr)) return false;
      const double squared_norm = Eigen::Map<const Eigen::VectorXd>(r.data(), residual.rows).squaredNorm();
      if (!std::isfinite(squared_norm)) return false;
      double rho[3] = {squared_norm, 1, 0};
      if (residual.loss != nullptr) residual.loss->Evaluate(squared_norm, rho);
      *cost += 0.5 * rho[0];
    }
    return true;
  }

  int CouplingBandwidth(const std::vector<int>& position) const {
    int bandwidth = 0;
    const auto widen = [&](int low, int high) { bandwidth = std::max(bandwidth, high - low); };
    const auto span = [&](const auto& blocks, const auto& dense_of) {
      int low = -1;
      int high = -1;
      for (const auto& block : blocks) {
        const int d = dense_of(block);
        if (d < 0 || position[static_cast<size_t>(d)] < 0) continue;
        const int at = position[static_cast<size_t>(d)];
        low = low < 0 ? at : std::min(low, at);
        high = std::max(high, at);
      }
      widen(low, high);
    };
    for (const Residual& residual : residuals) span(residual.slots, [](const Slot& slot) { return slot.dense; });
    for (const EliminatedBlock& block : eliminated) span(block.coupled, [](int d) { return d; });
    return bandwidth;
  }
};

BlockSystem::BlockSystem(ceres::Problem* problem, BlockLayout layout, const RankThreshold& threshold)
    : impl_(std::make_unique<Impl>(problem, std::move(layout), threshold)) {}

BlockSystem::~BlockSystem() = default;

bool BlockSystem::Reduce(double* cost) { return impl_->Reduce(cost); }
const Eigen::MatrixXd& BlockSystem::H() const { return impl_->H; }
const Eigen::VectorXd& BlockSystem::b() const { return impl_->b; }
void BlockSystem::MoveReducedTo(Eigen::MatrixXd* H, Eigen::VectorXd* b) {
  *H = std::move(impl_->H);
  H->triangularView<Eigen::StrictlyLower>() = H->transpose();
  *b = std::move(impl_->b);
}
int BlockSystem::dense_dim() const { return impl_->dense_dim; }
int BlockSystem::dim() const {
  return impl_->eliminated.empty() ? impl_->dense_dim
                                   : impl_->eliminated.back().columns.offset + impl_->eliminated.back().columns.size;
}
int BlockSystem::dense_offset(int k) const { return impl_->dense[static_cast<size_t>(k)].offset; }
int BlockSystem::dense_size(int k) const { return impl_->dense[static_cast<size_t>(k)].size; }
void BlockSystem::BackSubstitute(const Eigen::VectorXd& dx_dense, Eigen::VectorXd* dx) const {
  impl_->BackSubstitute(dx_dense, dx);
}
bool BlockSystem::Cost(double* cost) { return impl_->Cost(cost); }
int BlockSystem::CouplingBandwidth(const std::vector<int>& position) const {
  return impl_->CouplingBandwidth(position);
}

}  // namespace vio::marginalization
