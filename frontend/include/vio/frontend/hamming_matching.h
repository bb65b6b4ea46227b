#pragma once
// Matching binary descriptors (BRISK: 64 bytes) by Hamming distance: mutual
// nearest neighbours, optionally among given candidate pairs only. With all
// pairs it returns what cv::BFMatcher(NORM_HAMMING, crossCheck=true) returns
// (ties go to the lowest index on both sides); with candidates it costs what
// the candidates cost instead of every pair.
#include <vector>

#include <opencv2/core.hpp>

namespace vio::frontend {

/// Per query row, the train rows it may match, increasing.
using MatchCandidates = std::vector<std::vector<int>>;

/// Pairs (q, t) where t is q's nearest train row and q is t's nearest query
/// row, both among the admissible pairs (all pairs when `candidates` is null),
/// at Hamming distance <= max_bits; ordered by query row. `query` and `train`
/// are CV_8U with the same number of columns; `candidates`, when given, has
/// one list per query row.
std::vector<cv::DMatch> MatchMutualNearest(const cv::Mat& query, const cv::Mat& train, int max_bits,
                                           const MatchCandidates* candidates = nullptr);

}  // namespace vio::frontend
