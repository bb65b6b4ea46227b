#pragma once
// Shape checks shared by the reference filters and the equivalence code:
// bad input (a caller's matrix of the wrong size) is an exception naming the
// file, line and matrix.
#include <Eigen/Core>
#include <sstream>
#include <stdexcept>

#include "vio/marginalization/gaussian_state.h"

namespace vio::marginalization::internal {

/// (M + M^T) / 2: removes the round-off asymmetry of a computed covariance.
inline Eigen::MatrixXd Symmetrized(const Eigen::MatrixXd& M) { return 0.5 * (M + M.transpose()); }

inline void RequireShape(const Eigen::MatrixXd& m, Eigen::Index rows, Eigen::Index cols, const char* what,
                         const char* file, int line) {
  if (m.rows() != rows || m.cols() != cols) {
    std::ostringstream message;
    message << file << ":" << line << ": " << what << " is " << m.rows() << "x" << m.cols() << ", expected "
            << rows << "x" << cols;
    throw std::invalid_argument(message.str());
  }
}

inline void RequireInput(bool ok, const char* condition, const char* file, int line) {
  if (!ok) {
    std::ostringstream message;
    message << file << ":" << line << ": bad input: " << condition << " does not hold";
    throw std::invalid_argument(message.str());
  }
}

}  // namespace vio::marginalization::internal

#define VIO_REQUIRE_SHAPE(m, rows, cols) \
  ::vio::marginalization::internal::RequireShape((m), (rows), (cols), #m, __FILE__, __LINE__)
#define VIO_REQUIRE_INPUT(condition) \
  ::vio::marginalization::internal::RequireInput((condition), #condition, __FILE__, __LINE__)

namespace vio::marginalization::internal {

/// A finite Gaussian with a square covariance.
inline void RequireGaussian(const Gaussian& state) {
  VIO_REQUIRE_SHAPE(state.covariance, state.covariance.rows(), state.covariance.rows());
  VIO_REQUIRE_INPUT(state.mean.allFinite() && state.covariance.allFinite());
}

}  // namespace vio::marginalization::internal
