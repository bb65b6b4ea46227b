// ChainSolver's block cyclic reduction (chain_solve.h) for a chain of
// bandwidth 0 or 1: the Schur complement of the chain in the order
// 1, 3, 5, ... (every other block), then every other of the remaining ones,
// ..., block 0 last. Eliminating block i couples its two remaining neighbours
// with each other and spreads its coupling to the rest (the poses its IMU
// factors touch) to them, so at level l a block couples about 2^(l+1) poses:
// the updates of the rest's Schur complement cost O(k log k)-sized products
// instead of the banded sweeps' chain x rest ones. A window's first speed/bias
// block, tied by the prior to every pose, stays until the end and so spreads
// that wide coupling to no other block.
#include <algorithm>

#include "vio/estimator/chain_solve.h"

namespace vio {

// The rest positions block c couples to, [lo, hi) from its first to its last
// non-zero entry (zeros between are kept), and that part of H_chain,rest. Only
// the columns the caller gives are read (a window's speed/bias block: its two
// poses), down H's columns (contiguous) for those before the chain block.
void ChainSolver::FindRestCoupling(const Eigen::MatrixXd& H, const ChainBlock& c, Reduced* block) const {
  // The rest positions within the columns the caller says may be non-zero.
  const auto position = [&](int column) {
    return static_cast<int>(std::lower_bound(rest_.begin(), rest_.end(), column) - rest_.begin());
  };
  const int begin = c.first_column < 0 ? 0 : position(c.first_column);
  const int end = c.end_column < 0 ? static_cast<int>(rest_.size()) : position(c.end_column);
  // H's entry (rest position p, chain column c.offset + t) from its upper triangle.
  const auto entry = [&](int p, int t) {
    const int col = rest_[static_cast<size_t>(p)];
    return col < c.offset ? H(col, c.offset + t) : H(c.offset + t, col);
  };
  int lo = end;
  for (int t = 0; t < c.size; ++t) {
    for (int p = begin; p < lo; ++p) {
      if (entry(p, t) != 0.0) {
        lo = p;
        break;
      }
    }
  }
  int hi = lo;
  for (int t = 0; t < c.size; ++t) {
    for (int p = end - 1; p >= hi; --p) {
      if (entry(p, t) != 0.0) {
        hi = p + 1;
        break;
      }
    }
  }
  block->lo = lo;
  block->hi = hi;
  block->W.resize(c.size, hi - lo);
  for (int t = 0; t < c.size; ++t) {
    for (int p = lo; p < hi; ++p) block->W(t, p - lo) = entry(p, t);
  }
}

// Block i's part of H and -b, its neighbours (none for bandwidth 0) and its
// coupling to the rest.
void ChainSolver::InitReduced(const Eigen::MatrixXd& H, const Eigen::VectorXd& b,
                              const std::vector<ChainBlock>& chain, int i, int bandwidth) {
  const int m = static_cast<int>(chain.size());
  const ChainBlock& c = chain[static_cast<size_t>(i)];
  Reduced& block = reduced_[static_cast<size_t>(i)];
  block.D = H.block(c.offset, c.offset, c.size, c.size).selfadjointView<Eigen::Upper>();
  block.r = -b.segment(c.offset, c.size);
  block.neighbour[0] = bandwidth > 0 && i > 0 ? i - 1 : -1;
  block.neighbour[1] = bandwidth > 0 && i + 1 < m ? i + 1 : -1;
  if (block.neighbour[0] >= 0) {
    const ChainBlock& left = chain[static_cast<size_t>(i - 1)];
    block.C[0] = H.block(left.offset, c.offset, left.size, c.size).transpose();
  }
  if (block.neighbour[1] >= 0) {
    const ChainBlock& right = chain[static_cast<size_t>(i + 1)];
    block.C[1] = H.block(c.offset, right.offset, c.size, right.size);
  }
  FindRestCoupling(H, c, &block);
}

// The block's rest coupling over [min(lo, block lo), max(hi, block hi)),
// zero where it had none.
void ChainSolver::WidenRest(int lo, int hi, Reduced* block) {
  if (block->hi <= block->lo) {
    block->lo = lo;
    block->hi = hi;
    block->W.setZero(block->W.rows(), hi - lo);
    return;
  }
  const int new_lo = std::min(lo, block->lo);
  const int new_hi = std::max(hi, block->hi);
  if (new_lo == block->lo && new_hi == block->hi) return;
  widened_.setZero(block->W.rows(), new_hi - new_lo);
  widened_.middleCols(block->lo - new_lo, block->hi - block->lo) = block->W;
  block->W.swap(widened_);
  block->lo = new_lo;
  block->hi = new_hi;
}

// Block i's Schur complement into its remaining neighbours and the rest:
// with D = L L^T, its rows become L^-1 times themselves (V = L^-1 C,
// U = L^-1 W, y = L^-1 r); a neighbour x takes D_x -= V_x^T V_x,
// r_x -= V_x^T y, W_x -= V_x^T U, the two neighbours couple by -V_a^T V_c,
// and the rest takes S -= U^T U, r_rest -= U^T y.
bool ChainSolver::EliminateReduced(int i) {
  Reduced& e = reduced_[static_cast<size_t>(i)];
  e.llt.compute(e.D);
  if (e.llt.info() != Eigen::Success) return false;
  const auto L = e.llt.matrixL();
  L.solveInPlace(e.r);
  const int n = e.hi - e.lo;
  if (n > 0) {
    L.solveInPlace(e.W);
    S_.block(e.lo, e.lo, n, n).selfadjointView<Eigen::Upper>().rankUpdate(e.W.transpose(), -1.0);
    dx_rest_.segment(e.lo, n).noalias() -= e.W.transpose() * e.r;
  }
  for (int side = 0; side < 2; ++side) {
    if (e.neighbour[side] >= 0) L.solveInPlace(e.C[side]);
  }
  for (int side = 0; side < 2; ++side) {
    if (e.neighbour[side] < 0) continue;
    Reduced& x = reduced_[static_cast<size_t>(e.neighbour[side])];
    const Eigen::MatrixXd& V = e.C[side];
    x.D.noalias() -= V.transpose() * V;
    x.r.noalias() -= V.transpose() * e.r;
    if (n > 0) {
      WidenRest(e.lo, e.hi, &x);
      x.W.middleCols(e.lo - x.lo, n).noalias() -= V.transpose() * e.W;
    }
    // x's neighbour on e's side is now e's other neighbour.
    const int other = e.neighbour[1 - side];
    x.neighbour[1 - side] = other;
    if (other < 0) continue;
    if (side == 0) {  // the new coupling, formed once for both
      Reduced& c = reduced_[static_cast<size_t>(other)];
      x.C[1].noalias() = -V.transpose() * e.C[1];
      c.C[0] = x.C[1].transpose();
    }
  }
  return true;
}

// Cyclic reduction of the chain, the dense solve of the rest's Schur
// complement, then each chain block from its remaining neighbours' and the
// rest's solution, in reverse order: L^T dx_i = y_i - V dx_neighbours - U dx_rest.
bool ChainSolver::SolveByReduction(const Eigen::MatrixXd& H, const Eigen::VectorXd& b,
                                   const std::vector<ChainBlock>& chain, int bandwidth, Eigen::VectorXd* dx) {
  const int m = static_cast<int>(chain.size());
  const int nr = static_cast<int>(rest_.size());
  GatherRestSquare(H);
  dx_rest_ = -b(rest_);
  reduced_.resize(static_cast<size_t>(m));
  for (int i = 0; i < m; ++i) InitReduced(H, b, chain, i, bandwidth);
  order_.clear();
  std::vector<int> remaining(static_cast<size_t>(m));
  for (int i = 0; i < m; ++i) remaining[static_cast<size_t>(i)] = i;
  while (remaining.size() > 1) {
    size_t kept = 0;
    for (size_t j = 0; j < remaining.size(); ++j) {
      if (j % 2 == 1) {
        order_.push_back(remaining[j]);
      } else {
        remaining[kept++] = remaining[j];
      }
    }
    remaining.resize(kept);
  }
  if (m > 0) order_.push_back(remaining.front());
  for (const int i : order_) {
    if (!EliminateReduced(i)) return false;
  }
  if (nr > 0 && !SolveRest(&dx_rest_)) return false;
  dx->resize(H.rows());
  (*dx)(rest_) = dx_rest_;
  for (auto it = order_.rbegin(); it != order_.rend(); ++it) {
    Reduced& e = reduced_[static_cast<size_t>(*it)];
    const int n = e.hi - e.lo;
    if (n > 0) e.r.noalias() -= e.W * dx_rest_.segment(e.lo, n);
    for (int side = 0; side < 2; ++side) {
      const int x = e.neighbour[side];
      if (x >= 0) e.r.noalias() -= e.C[side] * dx->segment(chain[static_cast<size_t>(x)].offset, e.C[side].cols());
    }
    e.llt.matrixU().solveInPlace(e.r);
    dx->segment(chain[static_cast<size_t>(*it)].offset, e.r.size()) = e.r;
  }
  return dx->allFinite();
}

}  // namespace vio
