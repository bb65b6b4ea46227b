#include "vio/marginalization/block_system.h"

#include <algorithm>
#include <tuple>
#include <unordered_map>
#include <utility>

#include <glog/logging.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "block_system_impl.h"

namespace vio::marginalization {

BlockSystem::Impl::Impl(ceres::Problem* p, BlockLayout l, const RankThreshold& t) : problem(p), threshold(t) {
  Build(std::move(l));
}

// The structure of `l`; the buffers (H, the eliminated blocks' parts, the
// scratch) keep their memory for a layout of the same sizes.
void BlockSystem::Impl::Build(BlockLayout l) {
  layout = std::move(l);
  dense.clear();
  dense_dim = 0;
  residuals.clear();
  residual_values.clear();
  residual_slots.clear();
  manifold_blocks.clear();
  // A lookup from variable block to its slot fields only: no order depends on the addresses.
  std::unordered_map<const double*, Slot> index;
  index.reserve(layout.dense.size() + layout.eliminated.size());
  for (size_t k = 0; k < layout.dense.size(); ++k) {
    dense.push_back({dense_dim, problem->ParameterBlockTangentSize(layout.dense[k])});
    dense_dim += dense.back().size;
    index[layout.dense[k]].dense = static_cast<int>(k);
  }
  int col = dense_dim;
  ResizeEliminated(layout.eliminated.size());
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
  for (Residual& residual : residuals) {  // the shared arrays are complete: point into them
    residual.values = residual_values.data() + residual.first;
    residual.slots.data = residual_slots.data() + residual.first;
  }
  for (EliminatedBlock& block : eliminated) {
    std::sort(block.coupled.begin(), block.coupled.end());
    block.coupled.erase(std::unique(block.coupled.begin(), block.coupled.end()), block.coupled.end());
    if (block.W.size() < block.coupled.size()) block.W.resize(block.coupled.size());  // extra ones unused, kept
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
  structure_found = false;
}

// `count` eliminated blocks, those beyond it kept aside with their buffers
// (a marginalization's system is re-laid out for a different count each time).
void BlockSystem::Impl::ResizeEliminated(size_t count) {
  while (eliminated.size() > count) {
    spare_eliminated.push_back(std::move(eliminated.back()));
    eliminated.pop_back();
  }
  while (eliminated.size() < count) {
    if (spare_eliminated.empty()) {
      eliminated.emplace_back();
    } else {
      eliminated.push_back(std::move(spare_eliminated.back()));
      spare_eliminated.pop_back();
    }
  }
  for (EliminatedBlock& block : eliminated) block.coupled.clear();
}

// The residual's slots; returns the scratch its tangent Jacobians and its
// ambient ones (blocks with a manifold) need.
std::pair<size_t, size_t> BlockSystem::Impl::AddResidual(ceres::ResidualBlockId id, const std::unordered_map<const double*, Slot>& index) {
  Residual& residual = residuals.emplace_back();
  residual.id = id;
  const ceres::CostFunction* cost = problem->GetCostFunctionForResidualBlock(id);
  residual.cost = cost;
  residual.loss = problem->GetLossFunctionForResidualBlock(id);
  residual.on_tangents = dynamic_cast<const TangentCostFunction*>(cost);
  residual.rows = cost->num_residuals();
  problem->GetParameterBlocksForResidualBlock(id, &parameter_blocks);
  residual.first = static_cast<int>(residual_values.size());
  residual.slots.size = parameter_blocks.size();
  residual_values.insert(residual_values.end(), parameter_blocks.begin(), parameter_blocks.end());
  int jacobian = 0;
  int ambient = 0;
  for (const double* value : parameter_blocks) {
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
    residual_slots.push_back(slot);
  }
  if (residual.eliminated >= 0) {
    for (size_t k = residual.first; k < residual_slots.size(); ++k) {
      const Slot& slot = residual_slots[k];
      if (slot.dense >= 0) eliminated[residual.eliminated].coupled.push_back(slot.dense);
    }
  }
  // With a loss, as any other residual; a prior gives no tangent Jacobians itself.
  if (residual.loss == nullptr && residual.on_tangents == nullptr) {
    residual.prior = dynamic_cast<const MarginalizationPrior*>(cost);
  }
  r.resize(std::max(r.size(), static_cast<size_t>(residual.rows)));
  jacobian_pointers.resize(std::max(jacobian_pointers.size(), parameter_blocks.size()));
  if (residual.prior != nullptr) return {0, 0};  // from its information (AddPrior): no Jacobian scratch
  return {static_cast<size_t>(jacobian), static_cast<size_t>(ambient) * parameter_blocks.size()};
}

/// Schur complement of the eliminated blocks into (H, b), block by block:
/// with H_inv = S S^T, U = [W_1; ...; W_m] S, the update is one rank-n
/// update H -= U U^T over the coupled columns (in place over their span,
/// with zero rows in its gaps, grouped by row range: SubtractPendingUpdates;
/// pair by pair when the span is mostly gaps) and b -= U S^T b_e.
void BlockSystem::Impl::Eliminate() {
  pending.clear();
  pending_u_used = 0;
  for (EliminatedBlock& block : eliminated) {
    PseudoInverseInto(block.H, threshold, &block.H_inv);
    factor.compute(block.H_inv);
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
    const Eigen::Map<Eigen::MatrixXd> U =
        TimesFactor(StackCouplings(block, contiguous ? first : -1, contiguous ? span : rows));
    c.noalias() = factor.matrixU() * block.b;
    if (contiguous) {
      b.segment(first, span).noalias() -= U * c;
      KeepPendingUpdate(first, U);
    } else {
      SubtractPackedUpdate(block, U);
    }
  }
  SubtractPendingUpdates();
}

// U = the block's couplings W stacked: at their columns' offsets from
// `first` over `rows` rows (zero rows in the gaps), or packed one after the
// other when `first` is -1.
Eigen::Map<Eigen::MatrixXd> BlockSystem::Impl::StackCouplings(const EliminatedBlock& block, int first, int rows) {
  const auto size = static_cast<size_t>(rows) * static_cast<size_t>(block.columns.size);
  if (u_buffer.size() < size) u_buffer.resize(size);
  Eigen::Map<Eigen::MatrixXd> U(u_buffer.data(), rows, block.columns.size);
  if (first >= 0) U.setZero();
  for (size_t p = 0, packed = 0; p < block.coupled.size(); packed += block.W[p].rows(), ++p) {
    const Eigen::Index row = first >= 0 ? dense[block.coupled[p]].offset - first : static_cast<Eigen::Index>(packed);
    U.middleRows(row, block.W[p].rows()) = block.W[p];
  }
  return U;
}

// U times the lower factor of the block's H_inv (in place, or into ul_buffer).
Eigen::Map<Eigen::MatrixXd> BlockSystem::Impl::TimesFactor(Eigen::Map<Eigen::MatrixXd> U) {
  if (U.cols() != 3) {
    U = U * factor.matrixL();
    return U;
  }
  // A landmark: the 3x3 factor on fixed-size, coefficient by coefficient.
  const Eigen::Matrix3d L = factor.matrixL();
  if (ul_buffer.size() < static_cast<size_t>(U.size())) ul_buffer.resize(static_cast<size_t>(U.size()));
  Eigen::Map<Eigen::MatrixXd> UL(ul_buffer.data(), U.rows(), 3);
  UL.noalias() = U.lazyProduct(L);
  return UL;
}

// U kept for SubtractPendingUpdates, after the earlier blocks' in pending_u.
void BlockSystem::Impl::KeepPendingUpdate(int first, const Eigen::Map<Eigen::MatrixXd>& U) {
  const auto size = static_cast<size_t>(U.size());
  if (pending_u.size() < pending_u_used + size) pending_u.resize(pending_u_used + size);
  std::copy(U.data(), U.data() + size, pending_u.begin() + static_cast<std::ptrdiff_t>(pending_u_used));
  pending.push_back({first, static_cast<int>(U.rows()), static_cast<int>(U.cols()), pending_u_used});
  pending_u_used += size;
}

namespace {

// column[i] -= u0[i] v0 + u1[i] v1 + u2[i] v2 for i < rows, summed in that
// order from zero as SubtractPackedUpdate's loop over U's columns sums it.
void SubtractProducts3(const double* u0, const double* u1, const double* u2, double v0, double v1, double v2,
                       int rows, double* column) {
  for (int i = 0; i < rows; ++i) column[i] -= ((0.0 + u0[i] * v0) + u1[i] * v1) + u2[i] * v2;
}

}  // namespace

// b -= U c and H -= U U^T block pair by block pair, U packed (StackCouplings).
// Each entry of U U^T is summed over U's columns in order from zero, as the
// blocked rank update summed it into a zeroed buffer: the same values,
// without an n x n buffer to clear and scatter for each block.
void BlockSystem::Impl::SubtractPackedUpdate(const EliminatedBlock& block, const Eigen::Map<Eigen::MatrixXd>& U) {
  for (size_t p = 0, rp = 0; p < block.coupled.size(); rp += dense[block.coupled[p]].size, ++p) {
    const Columns& a = dense[block.coupled[p]];
    b.segment(a.offset, a.size).noalias() -= U.middleRows(rp, a.size) * c;
  }
  const Eigen::Index depth = U.cols();
  for (size_t p = 0, rp = 0; p < block.coupled.size(); rp += dense[block.coupled[p]].size, ++p) {
    const Columns& a = dense[block.coupled[p]];
    for (size_t q = p, rq = rp; q < block.coupled.size(); rq += dense[block.coupled[q]].size, ++q) {
      const Columns& c2 = dense[block.coupled[q]];
      for (int j = 0; j < c2.size; ++j) {
        // Within a diagonal block only its upper triangle (the rank update's).
        const int rows = p == q ? j + 1 : a.size;
        double* column = &H(a.offset, c2.offset + j);
        if (depth == 3) {  // a landmark's: the same sums, one vectorizable pass over the rows
          SubtractProducts3(&U(rp, 0), &U(rp, 1), &U(rp, 2), U(rq + j, 0), U(rq + j, 1), U(rq + j, 2), rows, column);
          continue;
        }
        for (int i = 0; i < rows; ++i) {
          double sum = 0.0;
          for (Eigen::Index k = 0; k < depth; ++k) sum += U(rp + i, k) * U(rq + j, k);
          column[i] -= sum;
        }
      }
    }
  }
}

// The contiguous updates H -= U U^T grouped by the rows they touch: one
// rank update with all the group's columns side by side (landmarks seen by
// the same states share the rows) instead of one three-column update each,
// which the blocked product handles at a fraction of its speed.
void BlockSystem::Impl::SubtractPendingUpdates() {
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
      columns += pending[end].cols;
    }
    // Mapped on a buffer that only grows: the groups' sizes vary, and a
    // matrix resized for each would reallocate (and page-fault) every time.
    const auto needed = static_cast<size_t>(group.rows * columns);
    if (stacked.size() < needed) stacked.resize(needed);
    Eigen::Map<Eigen::MatrixXd> stacked_columns(stacked.data(), group.rows, columns);
    columns = 0;
    for (size_t k = begin; k < end; ++k) {
      const Eigen::Map<const Eigen::MatrixXd> u(pending_u.data() + pending[k].offset, group.rows, pending[k].cols);
      stacked_columns.middleCols(columns, u.cols()) = u;
      columns += u.cols();
    }
    H.block(group.first, group.first, group.rows, group.rows)
        .selfadjointView<Eigen::Upper>()
        .rankUpdate(stacked_columns, -1.0);
  }
}

// The Schur update of one block through its pseudo-inverse, pair by pair.
void BlockSystem::Impl::EliminatePairwise(const EliminatedBlock& block) {
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
bool BlockSystem::Impl::Reduce(double* cost) {
  if (residuals.empty() || (layout.dense.empty() && layout.eliminated.empty())) return false;
  if (!Assemble(cost)) return false;
  Eliminate();
  return true;
}

void BlockSystem::Impl::BackSubstitute(const Eigen::VectorXd& dx_dense, Eigen::VectorXd* dx) const {
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
bool BlockSystem::Impl::Cost(double* cost) {
  *cost = 0;
  for (const Residual& residual : residuals) {
    if (!residual.cost->Evaluate(residual.values, r.data(), nullptr)) return false;
    const double squared_norm = Eigen::Map<const Eigen::VectorXd>(r.data(), residual.rows).squaredNorm();
    if (!std::isfinite(squared_norm)) return false;
    double rho[3] = {squared_norm, 1, 0};
    if (residual.loss != nullptr) residual.loss->Evaluate(squared_norm, rho);
    *cost += 0.5 * rho[0];
  }
  return true;
}

int BlockSystem::Impl::CouplingBandwidth(const std::vector<int>& position) const {
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

std::vector<std::pair<int, int>> BlockSystem::Impl::CoupledSpans(const std::vector<bool>& counted) const {
  const auto is_counted = [&](int d) { return counted.empty() || counted[static_cast<size_t>(d)]; };
  // Per block, the counted span so far; (-1, -1) while it has none.
  std::vector<std::pair<int, int>> spans(dense.size(), {-1, -1});
  for (size_t d = 0; d < dense.size(); ++d) {
    if (is_counted(static_cast<int>(d))) spans[d] = {static_cast<int>(d), static_cast<int>(d)};
  }
  const auto couple = [&](int low, int high, int d) {
    auto& span = spans[static_cast<size_t>(d)];
    span.first = span.first < 0 ? low : std::min(span.first, low);
    span.second = std::max(span.second, high);
  };
  const auto widen = [&](const auto& blocks, const auto& dense_of) {
    int low = -1;
    int high = -1;
    for (const auto& block : blocks) {
      const int d = dense_of(block);
      if (d < 0 || !is_counted(d)) continue;
      low = low < 0 ? d : std::min(low, d);
      high = std::max(high, d);
    }
    if (low < 0) return;
    for (const auto& block : blocks) {
      const int d = dense_of(block);
      if (d >= 0) couple(low, high, d);
    }
  };
  for (const Residual& residual : residuals) widen(residual.slots, [](const Slot& slot) { return slot.dense; });
  for (const EliminatedBlock& block : eliminated) widen(block.coupled, [](int d) { return d; });
  for (size_t d = 0; d < dense.size(); ++d) {
    if (spans[d].first < 0) spans[d] = {static_cast<int>(d), static_cast<int>(d)};
  }
  return spans;
}

BlockSystem::BlockSystem(ceres::Problem* problem, BlockLayout layout, const RankThreshold& threshold)
    : impl_(std::make_unique<Impl>(problem, std::move(layout), threshold)) {}

BlockSystem::~BlockSystem() = default;

void BlockSystem::Relayout(BlockLayout layout) { impl_->Build(std::move(layout)); }
void BlockSystem::Relayout(BlockLayout layout, const RankThreshold& threshold) {
  impl_->threshold = threshold;
  impl_->Build(std::move(layout));
}
ceres::Problem* BlockSystem::problem() const { return impl_->problem; }

bool BlockSystem::Reduce(double* cost) { return impl_->Reduce(cost); }
const Eigen::MatrixXd& BlockSystem::H() const { return impl_->H; }
const Eigen::VectorXd& BlockSystem::b() const { return impl_->b; }
void BlockSystem::MoveReducedTo(Eigen::MatrixXd* H, Eigen::VectorXd* b) {
  *H = std::move(impl_->H);
  H->triangularView<Eigen::StrictlyLower>() = H->transpose();
  *b = std::move(impl_->b);
}
int BlockSystem::dense_dim() const { return impl_->dense_dim; }
int BlockSystem::dense_offset(int k) const { return impl_->dense[static_cast<size_t>(k)].offset; }
int BlockSystem::dense_size(int k) const { return impl_->dense[static_cast<size_t>(k)].size; }
void BlockSystem::BackSubstitute(const Eigen::VectorXd& dx_dense, Eigen::VectorXd* dx) const {
  impl_->BackSubstitute(dx_dense, dx);
}
bool BlockSystem::Cost(double* cost) { return impl_->Cost(cost); }
int BlockSystem::CouplingBandwidth(const std::vector<int>& position) const {
  return impl_->CouplingBandwidth(position);
}
std::vector<std::pair<int, int>> BlockSystem::CoupledSpans(const std::vector<bool>& counted) const {
  return impl_->CoupledSpans(counted);
}

}  // namespace vio::marginalization
