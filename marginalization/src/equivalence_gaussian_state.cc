#include <glog/logging.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "vio/marginalization/gaussian_state.h"

namespace vio::marginalization {
namespace {

void RequireSize(const Eigen::VectorXd& v, int expected, const char* what) {
  if (v.size() != expected) {
    std::ostringstream message;
    message << __FILE__ << ":" << __LINE__ << ": " << what << " has " << v.size()
            << " entries, the layout expects " << expected;
    throw std::invalid_argument(message.str());
  }
}

}  // namespace

StateLayout& StateLayout::AddEuclidean(int size) {
  CHECK_GE(size, 0);
  blocks_.push_back({size, size, nullptr});
  ambient_size_ += size;
  tangent_size_ += size;
  return *this;
}

StateLayout& StateLayout::AddManifold(const ceres::Manifold* manifold) {
  CHECK(manifold != nullptr);
  blocks_.push_back({manifold->AmbientSize(), manifold->TangentSize(), manifold});
  ambient_size_ += manifold->AmbientSize();
  tangent_size_ += manifold->TangentSize();
  return *this;
}

StateLayout& StateLayout::Append(const StateLayout& other) {
  blocks_.insert(blocks_.end(), other.blocks_.begin(), other.blocks_.end());
  ambient_size_ += other.ambient_size_;
  tangent_size_ += other.tangent_size_;
  return *this;
}

StateLayout StateLayout::Slice(int first, int count) const {
  CHECK(first >= 0 && count >= 0 && first + count <= static_cast<int>(blocks_.size()))
      << "Slice(" << first << ", " << count << ") of " << blocks_.size() << " blocks";
  StateLayout slice;
  for (int i = first; i < first + count; ++i) {
    slice.blocks_.push_back(blocks_[i]);
    slice.ambient_size_ += blocks_[i].ambient_size;
    slice.tangent_size_ += blocks_[i].tangent_size;
  }
  return slice;
}

Eigen::VectorXd StateLayout::Plus(const Eigen::VectorXd& x, const Eigen::VectorXd& delta) const {
  RequireSize(x, ambient_size_, "StateLayout::Plus: x");
  RequireSize(delta, tangent_size_, "StateLayout::Plus: delta");
  Eigen::VectorXd result = x;
  int ambient = 0, tangent = 0;
  for (const StateBlock& block : blocks_) {
    if (block.manifold == nullptr) {
      result.segment(ambient, block.ambient_size) += delta.segment(tangent, block.tangent_size);
    } else {
      CHECK(block.manifold->Plus(x.data() + ambient, delta.data() + tangent, result.data() + ambient));
    }
    ambient += block.ambient_size;
    tangent += block.tangent_size;
  }
  return result;
}

Eigen::VectorXd StateLayout::Minus(const Eigen::VectorXd& y, const Eigen::VectorXd& x) const {
  RequireSize(y, ambient_size_, "StateLayout::Minus: y");
  RequireSize(x, ambient_size_, "StateLayout::Minus: x");
  Eigen::VectorXd result(tangent_size_);
  int ambient = 0, tangent = 0;
  for (const StateBlock& block : blocks_) {
    if (block.manifold == nullptr) {
      result.segment(tangent, block.tangent_size) =
          y.segment(ambient, block.ambient_size) - x.segment(ambient, block.ambient_size);
    } else {
      CHECK(block.manifold->Minus(y.data() + ambient, x.data() + ambient, result.data() + tangent));
    }
    ambient += block.ambient_size;
    tangent += block.tangent_size;
  }
  return result;
}

Deviation Compare(const Gaussian& a, const Gaussian& b, const StateLayout& layout,
                  const Eigen::VectorXd& linearization_point) {
  const int n = layout.TangentSize();
  if (a.covariance.rows() != n || a.covariance.cols() != n || b.covariance.rows() != n ||
      b.covariance.cols() != n) {
    std::ostringstream message;
    message << __FILE__ << ":" << __LINE__ << ": Compare: covariances are " << a.covariance.rows() << "x"
            << a.covariance.cols() << " and " << b.covariance.rows() << "x" << b.covariance.cols()
            << ", the layout has tangent size " << n;
    throw std::invalid_argument(message.str());
  }
  const double step = layout.Minus(b.mean, linearization_point).norm();
  const double spread = std::sqrt(std::max(b.covariance.trace(), 0.0));
  const double mean_scale = std::max({step, spread, std::numeric_limits<double>::min()});
  const double covariance_scale = std::max(b.covariance.norm(), std::numeric_limits<double>::min());
  return {layout.Minus(a.mean, b.mean).norm() / mean_scale,
          (a.covariance - b.covariance).norm() / covariance_scale};
}

namespace {

/// The larger of two deviations; NaN (a failed computation) wins.
double MaxOrNan(double a, double b) {
  if (std::isnan(a) || std::isnan(b)) return std::numeric_limits<double>::quiet_NaN();
  return std::max(a, b);
}

}  // namespace

Deviation Max(const Deviation& a, const Deviation& b) {
  return {MaxOrNan(a.mean, b.mean), MaxOrNan(a.covariance, b.covariance)};
}

}  // namespace vio::marginalization
