#include "vio/marginalization/marginalizer.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include <ceres/crs_matrix.h>
#include <glog/logging.h>

namespace vio::marginalization {
namespace {

using BlockSet = std::unordered_set<const double*>;

/// The residual blocks C2 touching the marginalized blocks and how the
/// variable parameter blocks they touch split into kept and marginalized.
struct MarkovBlanket {
  /// Every residual block touching a marginalized block, in problem order.
  std::vector<ceres::ResidualBlockId> residual_blocks;
  /// Variable blanket blocks, in order of first appearance.
  std::vector<double*> kept;
  /// Variable marginalized blocks that share no residual block with one
  /// another: eliminated block by block.
  std::vector<double*> marg_uncoupled;
  /// The remaining variable marginalized blocks: eliminated densely.
  std::vector<double*> marg_dense;
};

bool IsVariable(const ceres::Problem& problem, const double* block) {
  return !problem.IsParameterBlockConstant(block) && problem.ParameterBlockTangentSize(block) > 0;
}

std::vector<double*> UniqueBlocksInProblem(const ceres::Problem& problem,
                                           const std::vector<double*>& blocks) {
  std::vector<double*> unique;
  BlockSet seen;
  for (double* block : blocks) {
    if (!problem.HasParameterBlock(block)) {
      std::ostringstream message;
      message << "marginalization: parameter block " << static_cast<const void*>(block)
              << " is not in the problem";
      throw std::invalid_argument(message.str());
    }
    if (seen.insert(block).second) {
      unique.push_back(block);
    }
  }
  return unique;
}

std::vector<ceres::ResidualBlockId> ResidualBlocksTouching(const ceres::Problem& problem,
                                                           const std::vector<double*>& marg,
                                                           const std::vector<ceres::ResidualBlockId>& order) {
  std::unordered_set<ceres::ResidualBlockId> touching;
  std::vector<ceres::ResidualBlockId> of_block;
  for (const double* block : marg) {
    problem.GetResidualBlocksForParameterBlock(block, &of_block);
    touching.insert(of_block.begin(), of_block.end());
  }
  // A fixed order, so that summation order (and the result) is reproducible.
  std::vector<ceres::ResidualBlockId> all = order;
  if (all.empty()) problem.GetResidualBlocks(&all);
  std::vector<ceres::ResidualBlockId> ordered;
  std::copy_if(all.begin(), all.end(), std::back_inserter(ordered),
               [&touching](ceres::ResidualBlockId id) { return touching.count(id) > 0; });
  CHECK_EQ(ordered.size(), touching.size()) << "residual_order misses residual blocks of the marginalized blocks";
  return ordered;
}

/// Greedy independent set of the coupling graph (two marginalized blocks are
/// coupled when a residual block touches both), smallest blocks first so the
/// landmarks of a marginalized frame are eliminated one by one.
void SplitMarginalized(const ceres::Problem& problem, const std::vector<double*>& marg_variable,
                       const std::unordered_map<const double*, BlockSet>& coupled,
                       MarkovBlanket* blanket) {
  std::vector<double*> by_size = marg_variable;
  std::stable_sort(by_size.begin(), by_size.end(), [&problem](double* a, double* b) {
    return problem.ParameterBlockTangentSize(a) < problem.ParameterBlockTangentSize(b);
  });
  BlockSet picked;
  for (double* block : by_size) {
    const auto neighbours = coupled.find(block);
    const bool independent =
        neighbours == coupled.end() ||
        std::none_of(neighbours->second.begin(), neighbours->second.end(),
                     [&picked](const double* other) { return picked.count(other) > 0; });
    if (independent) {
      picked.insert(block);
      blanket->marg_uncoupled.push_back(block);
    } else {
      blanket->marg_dense.push_back(block);
    }
  }
}

MarkovBlanket FindMarkovBlanket(const ceres::Problem& problem, const std::vector<double*>& marg,
                                const std::vector<ceres::ResidualBlockId>& order) {
  MarkovBlanket blanket;
  blanket.residual_blocks = ResidualBlocksTouching(problem, marg, order);
  const BlockSet marg_set(marg.begin(), marg.end());
  BlockSet kept_seen;
  std::unordered_map<const double*, BlockSet> coupled;
  std::vector<double*> touched;
  for (const ceres::ResidualBlockId residual_block : blanket.residual_blocks) {
    problem.GetParameterBlocksForResidualBlock(residual_block, &touched);
    std::vector<double*> marg_here;
    for (double* block : touched) {
      if (!IsVariable(problem, block)) {
        continue;
      }
      if (marg_set.count(block) > 0) {
        marg_here.push_back(block);
      } else if (kept_seen.insert(block).second) {
        blanket.kept.push_back(block);
      }
    }
    for (double* a : marg_here) {
      for (double* b : marg_here) {
        if (a != b) {
          coupled[a].insert(b);
        }
      }
    }
  }
  std::vector<double*> marg_variable;
  std::copy_if(marg.begin(), marg.end(), std::back_inserter(marg_variable),
               [&problem](double* block) { return IsVariable(problem, block); });
  SplitMarginalized(problem, marg_variable, coupled, &blanket);
  return blanket;
}

int TangentDim(const ceres::Problem& problem, const std::vector<double*>& blocks) {
  int dim = 0;
  for (const double* block : blocks) {
    dim += problem.ParameterBlockTangentSize(block);
  }
  return dim;
}

/// H = J^T J, b = J^T r of a CRS Jacobian, row by row: the rows are factors
/// touching a few blocks (an earlier prior, the one dense factor, comes from
/// its information instead: AddPrior).
NormalEquations NormalEquationsOf(const ceres::CRSMatrix& J, const std::vector<double>& r) {
  const int n = J.num_cols;
  NormalEquations eq{Eigen::MatrixXd::Zero(n, n), Eigen::VectorXd::Zero(n)};
  for (int i = 0; i < J.num_rows; ++i) {
    const int begin = J.rows[i], end = J.rows[i + 1];
    for (int a = begin; a < end; ++a) {
      eq.b[J.cols[a]] += J.values[a] * r[i];
      for (int c = begin; c < end; ++c) eq.H(J.cols[a], J.cols[c]) += J.values[a] * J.values[c];
    }
  }
  return eq;
}

/// An earlier marginalization prior without a loss: its normal equations come
/// from its information (O(n^2)) instead of its dense Jacobian (O(n^3)).
const MarginalizationPrior* AsPrior(const ceres::Problem& problem, ceres::ResidualBlockId id) {
  if (problem.GetLossFunctionForResidualBlock(id) != nullptr) return nullptr;
  return dynamic_cast<const MarginalizationPrior*>(problem.GetCostFunctionForResidualBlock(id));
}

/// Adds a prior's tangent normal equations into `eq` at the blanket columns
/// of its blocks (-1 in `column_of`: a constant block, skipped).
void AddPrior(const ceres::Problem& problem, ceres::ResidualBlockId id, const MarginalizationPrior& prior,
              const std::unordered_map<const double*, int>& column_of, NormalEquations* eq) {
  std::vector<double*> blocks;
  problem.GetParameterBlocksForResidualBlock(id, &blocks);
  Eigen::MatrixXd H;
  Eigen::VectorXd g;
  double cost = 0.0;
  if (!prior.TangentNormalEquations(blocks.data(), &H, &g, &cost)) {
    throw std::runtime_error("marginalization: a marginalization prior does not evaluate on the Markov blanket");
  }
  std::vector<int> columns(blocks.size(), -1);
  for (size_t i = 0; i < blocks.size(); ++i) {
    const auto found = column_of.find(blocks[i]);
    if (found != column_of.end()) columns[i] = found->second;
  }
  for (size_t i = 0; i < blocks.size(); ++i) {
    if (columns[i] < 0) continue;
    const int oi = prior.tangent_offset(static_cast<int>(i)), ti = prior.tangent_size(static_cast<int>(i));
    eq->b.segment(columns[i], ti) += g.segment(oi, ti);
    for (size_t j = 0; j < blocks.size(); ++j) {
      if (columns[j] < 0) continue;
      const int oj = prior.tangent_offset(static_cast<int>(j)), tj = prior.tangent_size(static_cast<int>(j));
      eq->H.block(columns[i], columns[j], ti, tj) += H.block(oi, oj, ti, tj);
    }
  }
}

/// H = J^T J and b = J^T r of the blanket's residual blocks, columns in the
/// order [kept, marg_dense, marg_uncoupled], on the tangent spaces. Earlier
/// priors are added from their information, the other blocks from
/// Problem::Evaluate's Jacobian.
NormalEquations Linearize(ceres::Problem* problem, const MarkovBlanket& blanket) {
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.apply_loss_function = true;
  std::unordered_map<const double*, int> column_of;
  int dim = 0;
  for (const auto* group : {&blanket.kept, &blanket.marg_dense, &blanket.marg_uncoupled}) {
    for (double* block : *group) {
      evaluate.parameter_blocks.push_back(block);
      column_of[block] = dim;
      dim += problem->ParameterBlockTangentSize(block);
    }
  }
  CHECK(!evaluate.parameter_blocks.empty()) << "an empty list would evaluate every block";
  std::vector<std::pair<ceres::ResidualBlockId, const MarginalizationPrior*>> priors;
  for (const ceres::ResidualBlockId id : blanket.residual_blocks) {
    if (const MarginalizationPrior* prior = AsPrior(*problem, id)) {
      priors.emplace_back(id, prior);
    } else {
      evaluate.residual_blocks.push_back(id);
    }
  }
  NormalEquations eq{Eigen::MatrixXd::Zero(dim, dim), Eigen::VectorXd::Zero(dim)};
  if (!evaluate.residual_blocks.empty()) {  // an empty list would evaluate every block
    double cost = 0.0;
    std::vector<double> residuals;
    ceres::CRSMatrix jacobian;
    if (!problem->Evaluate(evaluate, &cost, &residuals, nullptr, &jacobian)) {
      throw std::runtime_error("marginalization: Problem::Evaluate failed on the Markov blanket");
    }
    eq = NormalEquationsOf(jacobian, residuals);
  }
  for (const auto& [id, prior] : priors) AddPrior(*problem, id, *prior, column_of, &eq);
  return eq;
}

std::vector<MarginalizationPrior::Block> PriorBlocks(const ceres::Problem& problem,
                                                     const std::vector<double*>& kept) {
  std::vector<MarginalizationPrior::Block> blocks;
  for (const double* values : kept) {
    MarginalizationPrior::Block block;
    block.manifold = problem.GetManifold(values);
    block.x0.assign(values, values + problem.ParameterBlockSize(values));
    blocks.push_back(std::move(block));
  }
  return blocks;
}

/// FEJ: x0_i <- x_fe_i and r0 <- r0 + Jp_i (x_fe_i ⊟ x_i) for every kept block
/// with a first estimate.
void ReexpressAtFirstEstimates(const ceres::Problem& problem, const std::vector<double*>& kept,
                               const std::function<const double*(const double*)>& first_estimate,
                               const Eigen::MatrixXd& sqrt_information,
                               std::vector<MarginalizationPrior::Block>* blocks, Eigen::VectorXd* residual) {
  int offset = 0;
  for (size_t i = 0; i < kept.size(); ++i) {
    const int tangent = problem.ParameterBlockTangentSize(kept[i]);
    MarginalizationPrior::Block& block = (*blocks)[i];
    if (const double* first = first_estimate(kept[i])) {
      Eigen::VectorXd delta(tangent);
      if (block.manifold != nullptr) {
        CHECK(block.manifold->Minus(first, kept[i], delta.data()));
      } else {
        for (int k = 0; k < tangent; ++k) delta[k] = first[k] - kept[i][k];
      }
      *residual += sqrt_information.middleCols(offset, tangent) * delta;
      block.x0.assign(first, first + block.x0.size());
    }
    offset += tangent;
  }
}

/// Steps 2-4 of the header: linearize, Schur-complement, take the square root.
std::unique_ptr<MarginalizationPrior> BuildPrior(ceres::Problem* problem,
                                                 const MarkovBlanket& blanket,
                                                 const MarginalizationOptions& options) {
  const RankThreshold& threshold = options.rank_threshold;
  const int keep_dim = TangentDim(*problem, blanket.kept);
  const int dense_dim = TangentDim(*problem, blanket.marg_dense);
  std::vector<int> uncoupled_dims;
  for (const double* block : blanket.marg_uncoupled) {
    uncoupled_dims.push_back(problem->ParameterBlockTangentSize(block));
  }
  const NormalEquations full = Linearize(problem, blanket);
  const NormalEquations without_uncoupled = SchurComplementOfUncoupledBlocks(
      full.H, full.b, keep_dim + dense_dim, uncoupled_dims, threshold);
  const NormalEquations marginal =
      SchurComplement(without_uncoupled.H, without_uncoupled.b, keep_dim, dense_dim, threshold);
  SqrtInformation sqrt =
      SqrtInformationFromHessian(marginal.H, marginal.b, threshold, options.sqrt_method);
  if (sqrt.sqrt_information.rows() == 0) {
    return nullptr;
  }
  std::vector<MarginalizationPrior::Block> blocks = PriorBlocks(*problem, blanket.kept);
  if (options.first_estimate) {
    ReexpressAtFirstEstimates(*problem, blanket.kept, options.first_estimate, sqrt.sqrt_information, &blocks,
                              &sqrt.residual);
  }
  std::unique_ptr<MarginalizationPrior> prior =
      MarginalizationPrior::Create(std::move(blocks), std::move(sqrt.sqrt_information), std::move(sqrt.residual),
                                   std::move(sqrt.information));
  if (options.first_estimate) prior->HoldJacobianAtLinearizationPoint();
  return prior;
}

}  // namespace

MarginalizationResult ComputeMarginalization(ceres::Problem* problem,
                                             const std::vector<double*>& to_marginalize,
                                             const MarginalizationOptions& options) {
  CHECK(problem != nullptr);
  const std::vector<double*> marg = UniqueBlocksInProblem(*problem, to_marginalize);
  MarkovBlanket blanket = FindMarkovBlanket(*problem, marg, options.residual_order);
  MarginalizationResult result;
  result.marginalized_residual_blocks = blanket.residual_blocks;
  if (!blanket.kept.empty()) {
    result.prior = BuildPrior(problem, blanket, options);
  }
  if (result.prior != nullptr) {
    result.kept_blocks = std::move(blanket.kept);
  }
  return result;
}

ceres::ResidualBlockId MarginalizeBlocks(ceres::Problem* problem,
                                         const std::vector<double*>& to_marginalize,
                                         const MarginalizationOptions& options) {
  MarginalizationResult result = ComputeMarginalization(problem, to_marginalize, options);
  for (const double* block : UniqueBlocksInProblem(*problem, to_marginalize)) {
    problem->RemoveParameterBlock(block);
  }
  if (result.prior == nullptr) {
    return nullptr;
  }
  return problem->AddResidualBlock(result.prior.release(), nullptr, result.kept_blocks);
}

}  // namespace vio::marginalization
