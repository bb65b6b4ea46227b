#include "vio/frontend/hamming_matching.h"

#include <limits>

#include <glog/logging.h>
#include <opencv2/core/hal/hal.hpp>

namespace vio::frontend {

std::vector<cv::DMatch> MatchMutualNearest(const cv::Mat& query, const cv::Mat& train, int max_bits,
                                           const MatchCandidates* candidates) {
  std::vector<cv::DMatch> matches;
  if (query.empty() || train.empty()) return matches;
  CHECK(query.type() == CV_8U && train.type() == CV_8U && query.cols == train.cols) << "descriptor layouts differ";
  CHECK(candidates == nullptr || candidates->size() == static_cast<size_t>(query.rows)) << "one list per query row";
  constexpr int kNone = -1;
  constexpr int kFar = std::numeric_limits<int>::max();
  std::vector<int> query_best(static_cast<size_t>(query.rows), kNone), query_distance(query_best.size(), kFar);
  std::vector<int> train_best(static_cast<size_t>(train.rows), kNone), train_distance(train_best.size(), kFar);
  // Strict improvements over rows visited in increasing order keep the lowest
  // index among equally near ones, on both sides.
  auto visit = [&](int q, int t) {
    const int d = cv::hal::normHamming(query.ptr(q), train.ptr(t), query.cols);
    if (d < query_distance[q]) {
      query_distance[q] = d;
      query_best[q] = t;
    }
    if (d < train_distance[t]) {
      train_distance[t] = d;
      train_best[t] = q;
    }
  };
  for (int q = 0; q < query.rows; ++q) {
    if (candidates == nullptr) {
      for (int t = 0; t < train.rows; ++t) visit(q, t);
    } else {
      for (int t : (*candidates)[static_cast<size_t>(q)]) visit(q, t);
    }
  }
  for (int q = 0; q < query.rows; ++q) {
    const int t = query_best[q];
    if (t == kNone || train_best[t] != q || query_distance[q] > max_bits) continue;
    matches.emplace_back(q, t, static_cast<float>(query_distance[q]));
  }
  return matches;
}

}  // namespace vio::frontend
