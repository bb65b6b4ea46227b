#pragma once
// The dense Gauss-Newton system with a chain of blocks solved first (paper
// §2.2's normal equations, factored in a cheaper order). After the landmarks
// are Schur-eliminated, the speed/bias blocks of a window couple only through
// the IMU factors between consecutive states: their part of H is block-banded.
// Eliminating them first by a block-banded Cholesky leaves a Schur complement
// over the poses (and prior-tied landmarks) only, so the cubic dense work is
// over 6k columns instead of 15k for a window of k states. The solution is the
// same as a dense Cholesky of the whole system up to round-off.
//
// A chain of bandwidth 0 or 1 (a window's speed/bias blocks) is eliminated by
// block cyclic reduction (chain_reduction.cc): every other block first, then
// every other of those, ..., so that a block's coupling to the rest grows only
// with its level (2^l poses) instead of filling the whole chain x rest
// product: O(k log k)-sized updates where the banded sweeps cost O(k^2).
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

namespace vio {

/// S = L L^T in place on S's lower triangle (S symmetric, its lower triangle
/// read) by panels, each trailing update one wide rank update. False when a
/// pivot is not positive.
bool FactorLowerInPlace(Eigen::MatrixXd& S);

/// The columns of one block of the chain.
struct ChainBlock {
  int offset = 0;
  int size = 0;
  /// Among the columns not in the chain, [first_column, end_column) hold
  /// every non-zero of the block's rows (a superset is fine); -1: not known,
  /// all of them.
  int first_column = -1;
  int end_column = -1;
};

/// Solves H dx = -b, H symmetric positive definite given by its upper
/// triangle, with the `chain` blocks (in chain order, ascending columns)
/// eliminated first. `bandwidth`: no entry of H couples chain blocks more than
/// this many places apart in the chain. Keeps its buffers between solves (a
/// window's Gauss-Newton steps solve systems of one shape).
class ChainSolver {
 public:
  /// The chain's right-hand sides, one row block per chain block: row-major,
  /// so a block's rows are contiguous and its products run along them.
  using RowMajorMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

  /// False when a factor is not positive definite (the caller falls back to a
  /// dense solve); `dx` is then unspecified.
  bool Solve(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, const std::vector<ChainBlock>& chain, int bandwidth,
             Eigen::VectorXd* dx);

 private:
  /// One chain block during cyclic reduction: its part of the system while it
  /// remains, then (eliminated, with D = L L^T) L^-1 times its rows, kept for
  /// the back-substitution.
  struct Reduced {
    Eigen::MatrixXd D;                ///< diagonal block
    Eigen::LLT<Eigen::MatrixXd> llt;  ///< of D, once eliminated
    Eigen::MatrixXd C[2];             ///< coupling to the left / right remaining neighbour (its rows)
    int neighbour[2] = {-1, -1};      ///< chain index of that neighbour, -1 for none
    RowMajorMatrix W;                 ///< coupling to the rest positions [lo, hi)
    int lo = 0;
    int hi = 0;
    Eigen::VectorXd r;  ///< right-hand side (-b)
  };

  bool SolveByReduction(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, const std::vector<ChainBlock>& chain,
                        int bandwidth, Eigen::VectorXd* dx);
  void InitReduced(const Eigen::MatrixXd& H, const Eigen::VectorXd& b, const std::vector<ChainBlock>& chain, int i,
                   int bandwidth);
  void FindRestCoupling(const Eigen::MatrixXd& H, const ChainBlock& c, Reduced* block) const;
  bool EliminateReduced(int i);
  void WidenRest(int lo, int hi, Reduced* block);
  void GatherRestSquare(const Eigen::MatrixXd& H);
  bool FactorChain(const Eigen::MatrixXd& H, const std::vector<ChainBlock>& chain);
  /// N: the chain blocks' size when all share it at compile time, else Eigen::Dynamic.
  template <int N>
  void SolveChain();
  template <int N>
  void ForwardSolve(RowMajorMatrix* r);
  template <int N>
  void BackwardSolve(RowMajorMatrix* z);
  void GatherRest(const Eigen::MatrixXd& H, const std::vector<ChainBlock>& chain, int chain_dim);
  /// x <- S^-1 x, S_ (its upper triangle) factored in place; false when it is not positive definite.
  bool SolveRest(Eigen::VectorXd* x);
  template <int N>
  void SubtractCoupling();
  const Eigen::MatrixXd& L(int i, int j) const { return below_[i][i - j - 1]; }
  int First(int i) const { return i - bandwidth_ > 0 ? i - bandwidth_ : 0; }

  int bandwidth_ = 0;
  std::vector<int> rows_;  ///< first row of each chain block among the chain's columns
  std::vector<int> rest_;  ///< the columns not in the chain, ascending
  std::vector<Eigen::LLT<Eigen::MatrixXd>> diagonal_;  ///< L(i, i) L(i, i)^T
  std::vector<Eigen::MatrixXd> inverse_;  ///< L(i, i)^-1: a small dense product instead of a substitution
  std::vector<std::vector<Eigen::MatrixXd>> below_;    ///< below_[i][i - j - 1] = L(i, j), j < i in the band
  RowMajorMatrix B_;  ///< H_chain,rest
  RowMajorMatrix Z_;  ///< H_chain,chain^-1 H_chain,rest
  Eigen::MatrixXd S_;  ///< H_rest,rest - H_rest,chain Z (upper triangle formed; SolveRest factors it)
  RowMajorMatrix w_;  ///< H_chain,chain^-1 b_chain (one column)
  RowMajorMatrix scratch_;  ///< one row block of a right-hand side
  Eigen::VectorXd dx_rest_;
  std::vector<Reduced> reduced_;
  std::vector<int> order_;  ///< the cyclic reduction's elimination order
  RowMajorMatrix widened_;  ///< scratch of WidenRest
};

}  // namespace vio
