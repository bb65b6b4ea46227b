#include "block_system_impl.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include <glog/logging.h>

#include <Eigen/Core>

namespace vio::marginalization {
namespace {

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

// J_i^T J_j into the upper block triangle of H.
template <typename JacobianI, typename JacobianJ>
void BlockSystem::Impl::AddDensePair(const Slot& i, const Slot& j, const JacobianI& Ji, const JacobianJ& Jj) {
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
void BlockSystem::Impl::AddDenseProduct(const Slot& i, const Slot& j, const Product& product) {
  const Columns& a = dense[i.dense];
  const Columns& c = dense[j.dense];
  if (a.offset <= c.offset) {
    H.block(a.offset, c.offset, a.size, c.size) += product;
  } else {
    H.block(c.offset, a.offset, c.size, a.size) += product.transpose();
  }
}

bool BlockSystem::Impl::AddGeneric(const Residual& residual, double* cost) {
  if (!EvaluateOnTangents(residual, cost)) return false;
  // A stereo residual (3 rows on a pose's 6-, a landmark's 3- and the time
  // offset's 1-dimensional tangent) takes fixed-size products; every other
  // shape the dynamic ones.
  if (residual.rows == 3 && HasTangentsOf1Or3Or6(residual)) {
    Accumulate(residual, Eigen::Map<const Eigen::Vector3d>(r.data()), [&](const Slot& slot, const auto& use) {
      const double* data = jacobians.data() + slot.jacobian;
      if (slot.tangent == 6) {
        use(Eigen::Map<const Eigen::Matrix<double, 3, 6, Eigen::RowMajor>>(data));
      } else if (slot.tangent == 3) {
        use(Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(data));
      } else {
        use(Eigen::Map<const Eigen::Vector3d>(data));
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
// (ApplyLoss). False when the cost function fails or the cost is not finite
// (a non-finite residual makes it so); a non-finite Jacobian is caught once
// per assembly, on the sums it enters (AssembledFinite).
bool BlockSystem::Impl::EvaluateOnTangents(const Residual& residual, double* cost) {
  const int rows = residual.rows;
  const bool on_tangents = residual.on_tangents != nullptr;  // no ambient round trip
  for (size_t k = 0, ambient = 0; k < residual.slots.size; ++k) {
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
      on_tangents ? residual.on_tangents->EvaluateOnTangents(residual.values, r.data(), jacobian_pointers.data())
                  : residual.cost->Evaluate(residual.values, r.data(), jacobian_pointers.data());
  Eigen::Map<Eigen::VectorXd> res(r.data(), rows);
  if (!evaluated) return false;
  tangent_jacobians.clear();
  for (size_t k = 0; k < residual.slots.size; ++k) {
    const Slot& slot = residual.slots[k];
    if (!slot.variable()) continue;
    Eigen::Map<RowMajorMatrix> tangent(jacobians.data() + slot.jacobian, rows, slot.tangent);
    if (slot.plus_jacobian != nullptr && !on_tangents) {
      tangent.noalias() = Eigen::Map<const RowMajorMatrix>(jacobian_pointers[k], rows, slot.ambient) * *slot.plus_jacobian;
    }
    tangent_jacobians.emplace_back(tangent.data(), slot.tangent);
  }
  *cost = residual.loss == nullptr ? 0.5 * res.squaredNorm() : ApplyLoss(*residual.loss, res, tangent_jacobians);
  return std::isfinite(*cost);
}

// PlusJacobian of every variable block with a manifold at the current values.
bool BlockSystem::Impl::RefreshPlusJacobians() {
  for (size_t k = 0; k < manifold_blocks.size(); ++k) {
    const auto& [manifold, values] = manifold_blocks[k];
    plus_jacobians[k].resize(manifold->AmbientSize(), manifold->TangentSize());
    if (!manifold->PlusJacobian(values, plus_jacobians[k].data())) return false;
  }
  return true;
}

bool BlockSystem::Impl::HasTangentsOf1Or3Or6(const Residual& residual) {
  for (const Slot& slot : residual.slots) {
    if (slot.variable() && slot.tangent != 1 && slot.tangent != 3 && slot.tangent != 6) return false;
  }
  return true;
}

// One residual's J^T J and J^T r into H and b (dense blocks) and into the
// eliminated blocks' H, b and couplings W; with_jacobian(slot, use) calls
// use with the slot's Jacobian.
template <typename Residuals, typename WithJacobian>
void BlockSystem::Impl::Accumulate(const Residual& residual, const Residuals& res, const WithJacobian& with_jacobian) {
  for (size_t p = 0; p < residual.slots.size; ++p) {
    const Slot& i = residual.slots[p];
    if (!i.variable()) continue;
    with_jacobian(i, [&](const auto& Ji) {
      if (i.dense >= 0) {
        b.segment(dense[i.dense].offset, i.tangent).noalias() += Ji.transpose() * res;
        for (size_t q = p; q < residual.slots.size; ++q) {
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
// MarginalizationPrior::Linearize) without forming Jp T: its blocks' parts
// go where a residual's J_i^T J_j would (H, b, or the eliminated block's H, b
// and couplings W).
// `cost` null: not wanted (the prior's is then not formed).
bool BlockSystem::Impl::AddPrior(const Residual& residual, double* cost) {
  const MarginalizationPrior& prior = *residual.prior;
  if (!prior.Linearize(residual.values, &prior_linearization, /*with_cost=*/cost != nullptr)) return false;
  if (cost != nullptr) *cost = prior_linearization.cost;
  const int n = static_cast<int>(residual.slots.size);
  // use(block (i, j) of the prior's J^T J): the stored information itself
  // where both T are the identity (Euclidean blocks, FEJ), else T_i^T I_ij T_j.
  const auto with_part = [&](int i, int j, const auto& use) {
    if (prior_linearization.T[static_cast<size_t>(i)].size() == 0 &&
        prior_linearization.T[static_cast<size_t>(j)].size() == 0) {
      use(prior.information().block(prior.tangent_offset(i), prior.tangent_offset(j), prior.tangent_size(i),
                                    prior.tangent_size(j)));
    } else {
      prior.TangentHessianBlock(prior_linearization, i, j, &prior_part);
      use(prior_part);
    }
  };
  for (int i = 0; i < n; ++i) {
    const Slot& si = residual.slots[i];
    const auto g = prior_linearization.g.segment(prior.tangent_offset(i), si.tangent);
    if (si.eliminated >= 0) {
      EliminatedBlock& block = eliminated[si.eliminated];
      block.b += g;
      with_part(i, i, [&](const auto& part) { block.H += part; });
      for (int j = 0; j < n; ++j) {
        const Slot& sj = residual.slots[j];
        if (sj.dense >= 0) with_part(j, i, [&](const auto& part) { block.W[sj.coupling] += part; });
      }
    }
    if (si.dense < 0) continue;
    b.segment(dense[si.dense].offset, si.tangent) += g;
    for (int j = i; j < n; ++j) {
      const Slot& sj = residual.slots[j];
      if (sj.dense >= 0) with_part(i, j, [&](const auto& part) { AddDenseProduct(si, sj, part); });
    }
  }
  return true;
}

// The dense block pairs an assembly writes, as rectangles of H's upper block
// triangle (runs of adjacent blocks merged): a residual's pairs (a prior's
// too), the diagonal blocks, and for each eliminated block every pair over
// the span of its coupled blocks (its Schur update goes over that span, whose
// gap rows of U are zero; pair by pair it writes fewer). A superset is safe:
// the blocks are cleared, not assumed non-zero.
void BlockSystem::Impl::FindStructure() {
  const size_t m = dense.size();
  std::vector<char> coupled(m * m, 0);
  const auto pair = [&](int a, int c) { coupled[static_cast<size_t>(std::min(a, c)) * m + std::max(a, c)] = 1; };
  std::vector<int> reach(m);  // row block a: every column block up to reach[a] is written
  for (size_t a = 0; a < m; ++a) reach[a] = static_cast<int>(a);
  for (const Residual& residual : residuals) {
    for (const Slot& i : residual.slots) {
      if (i.dense < 0) continue;
      for (const Slot& j : residual.slots) {
        if (j.dense >= 0) pair(i.dense, j.dense);
      }
    }
  }
  for (const EliminatedBlock& block : eliminated) {
    if (block.coupled.empty()) continue;
    for (int a = block.coupled.front(); a <= block.coupled.back(); ++a) {
      reach[a] = std::max(reach[a], block.coupled.back());
    }
  }
  structure.clear();
  for (size_t a = 0; a < m; ++a) {
    for (size_t c = a; c < m; ++c) {
      if (!coupled[a * m + c] && static_cast<int>(c) > reach[a]) continue;
      const bool extends = !structure.empty() && structure.back().row == dense[a].offset &&
                           structure.back().col + structure.back().cols == dense[c].offset;
      if (extends) {
        structure.back().cols += dense[c].size;
      } else {
        structure.push_back({dense[a].offset, dense[c].offset, dense[a].size, dense[c].size});
      }
    }
  }
}

// Only H's upper triangle is read (the chain and dense solves, the rank
// updates); the diagonal blocks are written whole, so they are zeroed whole.
// When H is reused (a window's solver, step after step and frame after
// frame), H is already zero outside the blocks the last assembly wrote: only
// those are cleared. A system assembled once (a marginalization's) never
// finds its structure.
void BlockSystem::Impl::Zero() {
  const bool reused = H.rows() == dense_dim && H.cols() == dense_dim;  // not new, not moved out (MoveReducedTo)
  if (reused && written_known) {
    for (const Rectangle& r : written) H.block(r.row, r.col, r.rows, r.cols).setZero();
  } else {
    H.resize(dense_dim, dense_dim);
    H.triangularView<Eigen::Upper>().setZero();
    for (const Columns& c : dense) H.block(c.offset, c.offset, c.size, c.size).setZero();
  }
  written_known = reused;
  if (reused) {
    if (!structure_found) FindStructure();
    structure_found = true;
    written = structure;
  }
  b.setZero(dense_dim);
  for (EliminatedBlock& block : eliminated) {
    const int n = block.columns.size;
    block.H.setZero(n, n);
    block.b.setZero(n);
    for (size_t k = 0; k < block.coupled.size(); ++k) block.W[k].setZero(dense[block.coupled[k]].size, n);
  }
}

// Every Jacobian entry enters, squared, a diagonal entry of H or of an
// eliminated block's H: a non-finite one leaves a non-finite diagonal. One
// check of the sums instead of one per Jacobian entry.
bool BlockSystem::Impl::AssembledFinite() const {
  if (!H.diagonal().allFinite() || !b.allFinite()) return false;
  for (const EliminatedBlock& block : eliminated) {
    if (!block.H.diagonal().allFinite() || !block.b.allFinite()) return false;
  }
  return true;
}

// `cost` null: the cost is not wanted (a marginalization's).
bool BlockSystem::Impl::Assemble(double* cost) {
  if (!RefreshPlusJacobians()) return false;
  Zero();
  double total = 0;
  for (const Residual& residual : residuals) {
    double c = 0;
    if (!(residual.prior != nullptr ? AddPrior(residual, cost != nullptr ? &c : nullptr) : AddGeneric(residual, &c))) {
      return false;
    }
    total += c;
  }
  if (cost != nullptr) *cost = total;
  return AssembledFinite();
}

}  // namespace vio::marginalization
