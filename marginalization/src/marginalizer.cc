#include "vio/marginalization/marginalizer.h"

#include <algorithm>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include <glog/logging.h>

#include "vio/marginalization/block_system.h"

namespace vio::marginalization {
namespace {

using BlockSet = std::unordered_set<const double*>;

/// The residual blocks C2 touching the marginalized blocks and how the
/// variable parameter blocks they touch split into kept and marginalized.
struct MarkovBlanket {
  /// Every residual block touching a marginalized block, in problem order.
  std::vector<ceres::ResidualBlockId> residual_blocks;
  /// Variable blanket blocks: those in kept_order first, in that order, then the others in order of
  /// first appearance.
  std::vector<double*> kept;
  /// Each kept block's place in kept_order (its size when not listed).
  std::vector<size_t> kept_place;
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
  seen.reserve(blocks.size());
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
                                                           const std::vector<ceres::ResidualBlockId>& order,
                                                           bool order_is_exact) {
  if (order_is_exact) return order;  // FindMarkovBlanket checks that each touches a marginalized block
  std::unordered_set<ceres::ResidualBlockId> touching;
  touching.reserve(order.size());
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

/// Which marginalized blocks share a residual block: for marginalized block k
/// (its index in `marg`), its neighbours are neighbours[offsets[k]] up to
/// neighbours[offsets[k + 1]] (repeats possible). Flat arrays, no set per block.
struct Couplings {
  std::vector<int> offsets;
  std::vector<int> neighbours;

  /// From the coupled pairs (each in both directions).
  Couplings(size_t blocks, std::vector<std::pair<int, int>> pairs) : offsets(blocks + 1, 0) {
    std::sort(pairs.begin(), pairs.end());
    neighbours.reserve(pairs.size());
    for (const auto& [from, to] : pairs) {
      ++offsets[static_cast<size_t>(from) + 1];
      neighbours.push_back(to);
    }
    for (size_t k = 0; k < blocks; ++k) offsets[k + 1] += offsets[k];
  }
};

/// Greedy independent set of the coupling graph (two marginalized blocks are
/// coupled when a residual block touches both), smallest blocks first so the
/// landmarks of a marginalized frame are eliminated one by one. `marg_variable`:
/// indices into `marg`.
void SplitMarginalized(const ceres::Problem& problem, const std::vector<double*>& marg,
                       const std::vector<int>& marg_variable, const Couplings& coupled, MarkovBlanket* blanket) {
  std::vector<std::pair<int, int>> by_size;  // (tangent size, index)
  by_size.reserve(marg_variable.size());
  for (const int k : marg_variable) by_size.emplace_back(problem.ParameterBlockTangentSize(marg[static_cast<size_t>(k)]), k);
  std::stable_sort(by_size.begin(), by_size.end(),
                   [](const std::pair<int, int>& a, const std::pair<int, int>& b) { return a.first < b.first; });
  std::vector<char> picked(marg.size(), 0);
  for (const auto& [size, k] : by_size) {
    const auto first = coupled.neighbours.begin() + coupled.offsets[static_cast<size_t>(k)];
    const auto last = coupled.neighbours.begin() + coupled.offsets[static_cast<size_t>(k) + 1];
    const bool independent = std::none_of(first, last, [&picked](int other) { return picked[static_cast<size_t>(other)] != 0; });
    double* block = marg[static_cast<size_t>(k)];
    if (independent) {
      picked[static_cast<size_t>(k)] = 1;
      blanket->marg_uncoupled.push_back(block);
    } else {
      blanket->marg_dense.push_back(block);
    }
  }
}

/// The kept blocks listed in `order` first, in that order, then the others as they were; `place`:
/// each one's place in `order` (its size when not listed).
void OrderKept(const std::vector<const double*>& order, std::vector<double*>* kept, std::vector<size_t>* place) {
  std::unordered_map<const double*, size_t> position;
  position.reserve(order.size());
  for (size_t k = 0; k < order.size(); ++k) position.emplace(order[k], k);
  std::vector<std::pair<size_t, double*>> ranked;
  ranked.reserve(kept->size());
  for (double* block : *kept) {
    const auto it = position.find(block);
    ranked.emplace_back(it != position.end() ? it->second : order.size(), block);
  }
  std::stable_sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  place->clear();
  for (size_t k = 0; k < ranked.size(); ++k) {
    place->push_back(ranked[k].first);
    (*kept)[k] = ranked[k].second;
  }
}

MarkovBlanket FindMarkovBlanket(const ceres::Problem& problem, const std::vector<double*>& marg,
                                const MarginalizationOptions& options) {
  MarkovBlanket blanket;
  blanket.residual_blocks =
      ResidualBlocksTouching(problem, marg, options.residual_order, options.residual_order_is_exact);
  std::unordered_map<const double*, int> marg_index;
  marg_index.reserve(marg.size());
  for (size_t k = 0; k < marg.size(); ++k) marg_index.emplace(marg[k], static_cast<int>(k));
  // Whether each marginalized block is variable, looked up once (not once per residual touching it).
  std::vector<char> marg_is_variable(marg.size());
  for (size_t k = 0; k < marg.size(); ++k) marg_is_variable[k] = IsVariable(problem, marg[k]) ? 1 : 0;
  BlockSet kept_seen;
  std::vector<std::pair<int, int>> pairs;
  std::vector<double*> touched;
  std::vector<int> marg_here;
  for (const ceres::ResidualBlockId residual_block : blanket.residual_blocks) {
    problem.GetParameterBlocksForResidualBlock(residual_block, &touched);
    marg_here.clear();
    bool touches_marg = false;
    for (double* block : touched) {
      if (const auto it = marg_index.find(block); it != marg_index.end()) {
        touches_marg = true;
        if (marg_is_variable[static_cast<size_t>(it->second)] != 0) marg_here.push_back(it->second);
      } else if (kept_seen.count(block) == 0 && IsVariable(problem, block)) {  // a variable blanket block, first seen
        kept_seen.insert(block);
        blanket.kept.push_back(block);
      }
    }
    CHECK(touches_marg) << "residual_order_is_exact: a residual of the order touches no marginalized block";
    for (const int a : marg_here) {
      for (const int b : marg_here) {
        if (a != b) pairs.emplace_back(a, b);
      }
    }
  }
  OrderKept(options.kept_order, &blanket.kept, &blanket.kept_place);
  std::vector<int> marg_variable;
  for (size_t k = 0; k < marg.size(); ++k) {
    if (marg_is_variable[k] != 0) marg_variable.push_back(static_cast<int>(k));
  }
  SplitMarginalized(problem, marg, marg_variable, Couplings(marg.size(), std::move(pairs)), &blanket);
  return blanket;
}

int TangentDim(const ceres::Problem& problem, const std::vector<double*>& blocks) {
  int dim = 0;
  for (const double* block : blocks) {
    dim += problem.ParameterBlockTangentSize(block);
  }
  return dim;
}

/// H and b of the blanket's residual blocks over [kept, marg_dense] on the
/// tangent spaces, with the uncoupled marginalized blocks already
/// Schur-complemented out block by block: the assembly the Gauss-Newton step
/// uses (BlockSystem; earlier priors from their information, loss functions
/// as Ceres applies them).
NormalEquations ReducedBlanket(ceres::Problem* problem, const MarkovBlanket& blanket,
                               const MarginalizationOptions& options) {
  BlockLayout layout;
  layout.dense = blanket.kept;
  layout.dense.insert(layout.dense.end(), blanket.marg_dense.begin(), blanket.marg_dense.end());
  layout.eliminated = blanket.marg_uncoupled;
  layout.residuals = blanket.residual_blocks;
  std::optional<BlockSystem> own;
  BlockSystem* system = options.system;
  if (system != nullptr) {
    CHECK(system->problem() == problem) << "marginalization: a kept system of another problem";
    system->Relayout(std::move(layout), options.rank_threshold);
  } else {
    system = &own.emplace(problem, std::move(layout), options.rank_threshold);
  }
  if (!system->Reduce(/*cost=*/nullptr)) {
    throw std::runtime_error("marginalization: the Markov blanket's residuals do not evaluate (or are not finite)");
  }
  NormalEquations reduced;
  system->MoveReducedTo(&reduced.H, &reduced.b);
  return reduced;
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
void ReexpressAtFirstEstimates(const ceres::Problem& problem, const MarkovBlanket& blanket,
                               const std::vector<const double*>& first_estimates,
                               const Eigen::MatrixXd& sqrt_information,
                               std::vector<MarginalizationPrior::Block>* blocks, Eigen::VectorXd* residual) {
  const std::vector<double*>& kept = blanket.kept;
  int offset = 0;
  for (size_t i = 0; i < kept.size(); ++i) {
    const int tangent = problem.ParameterBlockTangentSize(kept[i]);
    MarginalizationPrior::Block& block = (*blocks)[i];
    const size_t place = blanket.kept_place[i];
    if (const double* first = place < first_estimates.size() ? first_estimates[place] : nullptr) {
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
  const NormalEquations without_uncoupled = ReducedBlanket(problem, blanket, options);
  const NormalEquations marginal =
      SchurComplement(without_uncoupled.H, without_uncoupled.b, keep_dim, dense_dim, threshold);
  SqrtInformation sqrt =
      SqrtInformationFromHessian(marginal.H, marginal.b, threshold, options.sqrt_method);
  if (sqrt.sqrt_information.rows() == 0) {
    return nullptr;
  }
  std::vector<MarginalizationPrior::Block> blocks = PriorBlocks(*problem, blanket.kept);
  const bool fej = !options.first_estimates.empty();
  if (fej) ReexpressAtFirstEstimates(*problem, blanket, options.first_estimates, sqrt.sqrt_information, &blocks, &sqrt.residual);
  std::unique_ptr<MarginalizationPrior> prior =
      MarginalizationPrior::Create(std::move(blocks), std::move(sqrt.sqrt_information), std::move(sqrt.residual),
                                   std::move(sqrt.information));
  if (fej) prior->HoldJacobianAtLinearizationPoint();
  return prior;
}

/// ComputeMarginalization of blocks that are in the problem, each once.
MarginalizationResult MarginalizationOfUnique(ceres::Problem* problem, const std::vector<double*>& marg,
                                              const MarginalizationOptions& options) {
  if (!options.first_estimates.empty() && options.first_estimates.size() != options.kept_order.size()) {
    throw std::invalid_argument("marginalization: first_estimates and kept_order differ in length");
  }
  MarkovBlanket blanket = FindMarkovBlanket(*problem, marg, options);
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

}  // namespace

MarginalizationResult ComputeMarginalization(ceres::Problem* problem,
                                             const std::vector<double*>& to_marginalize,
                                             const MarginalizationOptions& options) {
  CHECK(problem != nullptr);
  return MarginalizationOfUnique(problem, UniqueBlocksInProblem(*problem, to_marginalize), options);
}

ceres::ResidualBlockId MarginalizeBlocks(ceres::Problem* problem,
                                         const std::vector<double*>& to_marginalize,
                                         const MarginalizationOptions& options) {
  CHECK(problem != nullptr);
  const std::vector<double*> marg = UniqueBlocksInProblem(*problem, to_marginalize);
  MarginalizationResult result = MarginalizationOfUnique(problem, marg, options);
  const int residuals_before = problem->NumResidualBlocks();
  for (const double* block : marg) {
    problem->RemoveParameterBlock(block);
  }
  // Removing the blocks removed every residual on them: an exact order held them all.
  CHECK_EQ(static_cast<size_t>(residuals_before - problem->NumResidualBlocks()),
           result.marginalized_residual_blocks.size())
      << "residual_order misses residual blocks of the marginalized blocks";
  if (result.prior == nullptr) {
    return nullptr;
  }
  return problem->AddResidualBlock(result.prior.release(), nullptr, result.kept_blocks);
}

}  // namespace vio::marginalization
