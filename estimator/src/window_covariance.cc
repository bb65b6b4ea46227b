#include "vio/estimator/window_covariance.h"

#include <algorithm>

#include <Eigen/Cholesky>

#include "vio/estimator/window.h"

namespace vio {

std::optional<Eigen::MatrixXd> MarginalCovariance(ceres::Problem* problem, const GaussNewtonLayout& layout,
                                                  const std::vector<const double*>& blocks) {
  std::vector<int> offsets, sizes;
  int col = 0;
  for (const double* dense : layout.dense) {
    const int size = problem->ParameterBlockTangentSize(dense);
    const auto it = std::find(blocks.begin(), blocks.end(), dense);
    if (it != blocks.end()) {
      offsets.resize(blocks.size());
      sizes.resize(blocks.size());
      offsets[static_cast<size_t>(it - blocks.begin())] = col;
      sizes[static_cast<size_t>(it - blocks.begin())] = size;
    }
    col += size;
  }
  for (const double* block : blocks) {
    if (std::find(layout.dense.begin(), layout.dense.end(), block) == layout.dense.end()) return std::nullopt;
  }
  ReducedSystem system;
  if (!ReducedNormalEquations(problem, layout, &system)) return std::nullopt;
  const Eigen::LLT<Eigen::MatrixXd> llt(system.H);
  if (llt.info() != Eigen::Success) return std::nullopt;

  int dim = 0;
  for (int size : sizes) dim += size;
  Eigen::MatrixXd selector = Eigen::MatrixXd::Zero(system.H.rows(), dim);
  for (size_t k = 0, out = 0; k < blocks.size(); out += static_cast<size_t>(sizes[k]), ++k) {
    selector.block(offsets[k], static_cast<Eigen::Index>(out), sizes[k], sizes[k]).setIdentity();
  }
  const Eigen::MatrixXd columns = llt.solve(selector);
  Eigen::MatrixXd covariance = selector.transpose() * columns;
  covariance = 0.5 * (covariance + covariance.transpose()).eval();
  if (!covariance.allFinite()) return std::nullopt;
  return covariance;
}

std::optional<StateCovariance> NewestStateCovariance(Window& window) {
  if (window.states().empty()) return std::nullopt;
  const State& newest = window.states().rbegin()->second;
  const std::optional<Eigen::MatrixXd> covariance =
      MarginalCovariance(&window.problem(), window.Layout(), {newest.pose, newest.speed_bias});
  if (!covariance) return std::nullopt;
  StateCovariance out;
  out.id = newest.id;
  out.t_ns = newest.t_ns;
  out.covariance = *covariance;
  return out;
}

}  // namespace vio
