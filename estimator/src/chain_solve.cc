#include "vio/estimator/chain_solve.h"

#include <algorithm>

namespace vio {
namespace {

/// Panel width of FactorLowerInPlace: at n = 300 (the poses of a 50-state
/// window) 48-96 factor about 3 % faster than Eigen's 32.
constexpr Eigen::Index kRestPanel = 64;

/// A maximal run of consecutive columns among ascending ones.
struct Run {
  int column = 0;    ///< its first column
  int position = 0;  ///< the index of that column in the list
  int length = 0;
};

std::vector<Run> RunsOf(const std::vector<int>& columns) {
  std::vector<Run> runs;
  for (int k = 0; k < static_cast<int>(columns.size()); ++k) {
    if (!runs.empty() && columns[static_cast<size_t>(k)] == runs.back().column + runs.back().length) {
      ++runs.back().length;
    } else {
      runs.push_back({columns[static_cast<size_t>(k)], k, 1});
    }
  }
  return runs;
}

/// H's block (a, b) of a symmetric matrix stored in its upper triangle, for
/// a.offset < b.offset or a == b.
Eigen::MatrixXd UpperBlock(const Eigen::MatrixXd& H, const ChainBlock& a, const ChainBlock& b) {
  if (a.offset == b.offset) return H.block(a.offset, a.offset, a.size, a.size).selfadjointView<Eigen::Upper>();
  return H.block(a.offset, b.offset, a.size, b.size);
}

/// A chain block's matrix as an N x N one (N = Eigen::Dynamic: any size).
template <int N>
Eigen::Map<const Eigen::Matrix<double, N, N>> Fixed(const Eigen::MatrixXd& m) {
  return {m.data(), m.rows(), m.cols()};
}

/// Rows [at, at + a.rows()) of r -= a times rows [from, from + a.cols()):
/// a coefficient-based product along r's contiguous rows, unrolled when the
/// block size N is fixed (the blocked product's packing costs as much as the
/// product itself at 9 x 9).
template <int N, typename Matrix>
void SubtractProduct(const Matrix& a, int from, int at, ChainSolver::RowMajorMatrix* r) {
  const Eigen::Matrix<double, N, N> a_plain = a;  // a transpose evaluated: the product's inner loop reads it
  r->middleRows<N>(at, a.rows()) -= a_plain.lazyProduct(r->middleRows<N>(from, a.cols()));
}

/// Rows [at, at + a.rows()) of r <- a times themselves.
template <int N, typename Matrix>
void MultiplyInPlace(const Matrix& a, int at, ChainSolver::RowMajorMatrix* r, ChainSolver::RowMajorMatrix* scratch) {
  const Eigen::Matrix<double, N, N> a_plain = a;
  *scratch = a_plain.lazyProduct(r->middleRows<N>(at, a.cols()));
  r->middleRows<N>(at, a.rows()) = *scratch;
}

}  // namespace

/// S = L L^T in place on S's lower triangle, panel by panel: the panel's
/// diagonal block factored, its column block solved, the trailing matrix
/// updated by one rank-kRestPanel product (Eigen's blocked algorithm). Eigen's
/// LLT of an upper triangle factors the transposed, row-major matrix and takes
/// about 1.2x as long. False when a pivot is not positive.
bool FactorLowerInPlace(Eigen::MatrixXd& S) {
  const Eigen::Index n = S.rows();
  for (Eigen::Index p = 0; p < n; p += kRestPanel) {
    const Eigen::Index w = std::min(kRestPanel, n - p);
    Eigen::Ref<Eigen::MatrixXd> diagonal = S.block(p, p, w, w);
    const Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>, Eigen::Lower> panel(diagonal);  // in place
    if (panel.info() != Eigen::Success) return false;
    const Eigen::Index rest = n - p - w;
    if (rest == 0) break;
    auto below = S.block(p + w, p, rest, w);
    S.block(p, p, w, w).triangularView<Eigen::Lower>().transpose().solveInPlace<Eigen::OnTheRight>(below);
    S.bottomRightCorner(rest, rest).selfadjointView<Eigen::Lower>().rankUpdate(below, -1.0);
  }
  return true;
}

// Block-banded Cholesky H_cc = L L^T, block row by block row.
bool ChainSolver::FactorChain(const Eigen::MatrixXd& H, const std::vector<ChainBlock>& chain) {
  const int m = static_cast<int>(chain.size());
  diagonal_.resize(m);
  below_.resize(m);
  for (int i = 0; i < m; ++i) {
    below_[i].resize(static_cast<size_t>(i - First(i)));
    for (int j = First(i); j < i; ++j) {
      Eigen::MatrixXd a = UpperBlock(H, chain[j], chain[i]).transpose();
      for (int k = std::max(First(i), First(j)); k < j; ++k) a.noalias() -= L(i, k) * L(j, k).transpose();
      // L(i, j) L(j, j)^T = a
      below_[i][i - j - 1] = diagonal_[j].matrixL().solve(a.transpose()).transpose();
    }
    Eigen::MatrixXd d = UpperBlock(H, chain[i], chain[i]);
    for (int k = First(i); k < i; ++k) d.noalias() -= L(i, k) * L(i, k).transpose();
    diagonal_[i].compute(d);
    if (diagonal_[i].info() != Eigen::Success) return false;
  }
  inverse_.resize(m);
  for (int i = 0; i < m; ++i) {
    inverse_[i].setIdentity(diagonal_[i].rows(), diagonal_[i].rows());
    diagonal_[i].matrixL().solveInPlace(inverse_[i]);
  }
  return true;
}

// r <- L^-1 r, r with one row block per chain block (the diagonal blocks'
// inverses: a product instead of a substitution).
template <int N>
void ChainSolver::ForwardSolve(RowMajorMatrix* r) {
  for (int i = 0; i < static_cast<int>(diagonal_.size()); ++i) {
    for (int k = First(i); k < i; ++k) SubtractProduct<N>(Fixed<N>(L(i, k)), rows_[k], rows_[i], r);
    MultiplyInPlace<N>(Fixed<N>(inverse_[i]), rows_[i], r, &scratch_);
  }
}

// z <- L^-T z, z with one row block per chain block.
template <int N>
void ChainSolver::BackwardSolve(RowMajorMatrix* z) {
  const int m = static_cast<int>(diagonal_.size());
  for (int i = m - 1; i >= 0; --i) {
    for (int k = i + 1; k < std::min(m, i + bandwidth_ + 1); ++k) {
      SubtractProduct<N>(Fixed<N>(L(k, i)).transpose(), rows_[k], rows_[i], z);
    }
    MultiplyInPlace<N>(Fixed<N>(inverse_[i]).transpose(), rows_[i], z, &scratch_);
  }
}

// S = H_rr - H_rc Z with Z = H_cc^-1 H_cr, row block by chain block: chain
// block i touches only the rest columns its rows of H_cr are non-zero in (the
// IMU factors: two poses; a prior: the poses it spans), in runs of adjacent
// columns, so this costs nnz(H_cr) x rest instead of the chain x rest^2 of
// forming (L^-1 H_cr)^T (L^-1 H_cr). Only S's upper triangle is formed.
template <int N>
void ChainSolver::SubtractCoupling() {
  const int nr = static_cast<int>(rest_.size());
  for (size_t i = 0; i < rows_.size(); ++i) {
    const int size = static_cast<int>(diagonal_[i].rows());
    const auto coupled = [&](int j) { return j < nr && !B_.block(rows_[i], j, size, 1).isZero(0.0); };
    for (int first = 0; first < nr; ++first) {
      if (!coupled(first)) continue;
      int end = first + 1;
      while (coupled(end)) ++end;
      // The square part's upper triangle (all of S_ that is read), then the columns right of it.
      const auto B_run = B_.block<N, Eigen::Dynamic>(rows_[i], first, size, end - first).transpose();
      S_.block(first, first, end - first, end - first).triangularView<Eigen::Upper>() -=
          B_run * Z_.block<N, Eigen::Dynamic>(rows_[i], first, size, end - first);
      S_.block(first, end, end - first, nr - end).noalias() -=
          B_run * Z_.block<N, Eigen::Dynamic>(rows_[i], end, size, nr - end);
      first = end;
    }
  }
}

// B = H_chain,rest, copied block by block: a run of consecutive rest columns
// lies wholly before or after a chain block, so each piece is a block of H's
// upper triangle (or its transpose), read column by column.
void ChainSolver::GatherRest(const Eigen::MatrixXd& H, const std::vector<ChainBlock>& chain, int chain_dim) {
  const int nr = static_cast<int>(rest_.size());
  B_.resize(chain_dim, nr);
  const std::vector<Run> runs = RunsOf(rest_);
  for (size_t i = 0; i < chain.size(); ++i) {
    const ChainBlock& c = chain[i];
    for (const Run& run : runs) {
      auto to = B_.block(rows_[i], run.position, c.size, run.length);
      if (run.column < c.offset) {
        to = H.block(run.column, c.offset, run.length, c.size).transpose();
      } else {
        to = H.block(c.offset, run.column, c.size, run.length);
      }
    }
  }
  GatherRestSquare(H);
}

// The upper triangle of S = H_rest,rest, run by run.
void ChainSolver::GatherRestSquare(const Eigen::MatrixXd& H) {
  const int nr = static_cast<int>(rest_.size());
  S_.resize(nr, nr);
  const std::vector<Run> runs = RunsOf(rest_);
  for (size_t a = 0; a < runs.size(); ++a) {
    const Run& ra = runs[a];
    S_.block(ra.position, ra.position, ra.length, ra.length).triangularView<Eigen::Upper>() =
        H.block(ra.column, ra.column, ra.length, ra.length);
    for (size_t b = a + 1; b < runs.size(); ++b) {
      const Run& rb = runs[b];
      S_.block(ra.position, rb.position, ra.length, rb.length) = H.block(ra.column, rb.column, ra.length, rb.length);
    }
  }
}

// Z <- H_cc^-1 Z, w <- H_cc^-1 w, then S -= H_rc Z.
template <int N>
void ChainSolver::SolveChain() {
  ForwardSolve<N>(&Z_);
  BackwardSolve<N>(&Z_);
  ForwardSolve<N>(&w_);
  BackwardSolve<N>(&w_);
  SubtractCoupling<N>();
}

// x <- S^-1 x for the rest's Schur complement S (S_'s upper triangle), factored
// in place: its upper triangle mirrored into the lower one, which is factored.
bool ChainSolver::SolveRest(Eigen::VectorXd* x) {
  S_.triangularView<Eigen::StrictlyLower>() = S_.transpose();
  if (!FactorLowerInPlace(S_)) return false;
  S_.triangularView<Eigen::Lower>().solveInPlace(*x);
  S_.transpose().triangularView<Eigen::Upper>().solveInPlace(*x);
  return true;
}

// With H_cc = L L^T, Z = H_cc^-1 H_cr and w = H_cc^-1 b_c: the rest solves
// (H_rr - H_rc Z) dx_r = -(b_r - H_rc w), then dx_c = -(w + Z dx_r).
bool ChainSolver::Solve(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, const std::vector<ChainBlock>& chain,
                        int bandwidth, Eigen::VectorXd* dx) {
  const int n = static_cast<int>(H.rows());
  bandwidth_ = bandwidth;
  rows_.clear();
  std::vector<int> chain_columns;
  std::vector<bool> in_chain(static_cast<size_t>(n), false);
  for (const ChainBlock& block : chain) {
    rows_.push_back(static_cast<int>(chain_columns.size()));
    for (int c = block.offset; c < block.offset + block.size; ++c) {
      chain_columns.push_back(c);
      in_chain[c] = true;
    }
  }
  rest_.clear();
  for (int c = 0; c < n; ++c) {
    if (!in_chain[c]) rest_.push_back(c);
  }
  if (bandwidth <= 1) return SolveByReduction(H, b, chain, bandwidth, dx);
  if (!FactorChain(H, chain)) return false;
  const int nr = static_cast<int>(rest_.size());
  GatherRest(H, chain, static_cast<int>(chain_columns.size()));
  // Speed/bias blocks (9) on fixed-size products, any other chain generically.
  const bool nine = std::all_of(chain.begin(), chain.end(), [](const ChainBlock& c) { return c.size == 9; });
  Z_ = B_;
  w_ = b(chain_columns);
  if (nine) {
    SolveChain<9>();
  } else {
    SolveChain<Eigen::Dynamic>();
  }
  dx_rest_.resize(nr);
  if (nr > 0) {
    dx_rest_.noalias() = B_.transpose() * w_.col(0);
    dx_rest_ -= b(rest_);
    if (!SolveRest(&dx_rest_)) return false;
  }
  w_.col(0).noalias() += Z_ * dx_rest_;
  dx->resize(n);
  (*dx)(chain_columns) = -w_.col(0);
  (*dx)(rest_) = dx_rest_;
  return dx->allFinite();
}

}  // namespace vio
