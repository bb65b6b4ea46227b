// The parts of the BRISK front end that replace OpenCV calls: the segment-test
// score (against cv::FAST, which computes the same score), its sub-pixel
// refinement, and mutual-nearest Hamming matching (against cv::BFMatcher with
// cross check, and against a brute-force search over candidate pairs).
#include <random>
#include <set>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "vio/frontend/hamming_matching.h"
#include "vio/frontend/segment_test_corners.h"

namespace vio::frontend {
namespace {

// Blurred uniform noise: corners of every strength.
cv::Mat TexturedImage(int seed) {
  cv::Mat image(120, 160, CV_8UC1);
  cv::RNG rng(static_cast<std::uint64_t>(seed));
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(image, image, cv::Size(5, 5), 1.2);
  return image;
}

TEST(SegmentTestScore, EqualsTheResponseOfEveryFastCorner) {
  for (int seed : {1, 2}) {
    const cv::Mat image = TexturedImage(seed);
    std::vector<cv::KeyPoint> corners;
    // (cv::FAST sets the response only when it suppresses non-maxima.)
    cv::FAST(image, corners, 10, /*nonmaxSuppression=*/true, cv::FastFeatureDetector::TYPE_9_16);
    ASSERT_GT(corners.size(), 100u);
    for (const cv::KeyPoint& c : corners) {
      EXPECT_EQ(SegmentTestScore(image, static_cast<int>(c.pt.x), static_cast<int>(c.pt.y)),
                static_cast<int>(c.response))
          << c.pt;
    }
  }
}

// FAST at threshold t detects exactly the pixels whose score is >= t.
TEST(SegmentTestScore, ThresholdSelectsExactlyTheCornersFastFinds) {
  const cv::Mat image = TexturedImage(3);
  for (int threshold : {5, 12, 25}) {
    std::vector<cv::KeyPoint> corners;
    cv::FAST(image, corners, threshold, /*nonmaxSuppression=*/false, cv::FastFeatureDetector::TYPE_9_16);
    std::set<std::pair<int, int>> fast;
    for (const cv::KeyPoint& c : corners) fast.insert({static_cast<int>(c.pt.x), static_cast<int>(c.pt.y)});
    std::set<std::pair<int, int>> scored;
    for (int y = 3; y < image.rows - 3; ++y) {
      for (int x = 3; x < image.cols - 3; ++x) {
        if (SegmentTestScore(image, x, y) >= threshold) scored.insert({x, y});
      }
    }
    EXPECT_EQ(scored, fast) << "threshold " << threshold;
  }
}

TEST(SegmentTestScoreMap, ComputesEachPixelOnceAndAsTheFunctionDoes) {
  const cv::Mat image = TexturedImage(6);
  SegmentTestScoreMap scores(image);
  EXPECT_FALSE(scores.Known(50, 40));
  EXPECT_EQ(scores(50, 40), SegmentTestScore(image, 50, 40));
  EXPECT_TRUE(scores.Known(50, 40));
  EXPECT_EQ(scores(50, 40), SegmentTestScore(image, 50, 40));
  EXPECT_FALSE(scores.Known(51, 40));
}

TEST(SegmentTestScore, FlatImageScoresZero) {
  const cv::Mat flat(20, 20, CV_8UC1, cv::Scalar(100));
  EXPECT_EQ(SegmentTestScore(flat, 10, 10), 0);
}

TEST(RefineCorner, SymmetricNeighbourhoodStaysOnThePixel) {
  cv::Mat image(21, 21, CV_8UC1, cv::Scalar(40));
  cv::circle(image, cv::Point(10, 10), 1, cv::Scalar(220), cv::FILLED);  // a dot symmetric about (10, 10)
  cv::KeyPoint corner(cv::Point2f(10.0f, 10.0f), kBriskKeypointSizePx, -1.0f, 0.0f);
  SegmentTestScoreMap scores(image);
  RefineCorner(&scores, &corner);
  EXPECT_EQ(corner.pt, cv::Point2f(10.0f, 10.0f));
  EXPECT_GE(corner.response, static_cast<float>(SegmentTestScore(image, 10, 10)) - 1e-3f);
}

// The position moves at most one pixel and the response is the fitted
// quadratic's maximum: at least the fit's value at the pixel, which is close
// to the pixel's own score.
TEST(RefineCorner, MovesCornersByAtMostOnePixelToTheFittedMaximumAndLeavesTheBorderAlone) {
  const cv::Mat image = TexturedImage(4);
  int moved = 0, corners = 0, border = 0;
  SegmentTestScoreMap scores(image);
  for (cv::KeyPoint c : DetectSegmentTestCorners(10, &scores)) {
    const int x = static_cast<int>(c.pt.x), y = static_cast<int>(c.pt.y);
    const cv::KeyPoint before = c;
    RefineCorner(&scores, &c);
    if (x < 4 || y < 4 || x >= image.cols - 4 || y >= image.rows - 4) {  // too near the border: unrefined
      EXPECT_EQ(c.pt, before.pt);
      EXPECT_EQ(c.response, before.response);
      ++border;
      continue;
    }
    ++corners;
    EXPECT_LE(std::abs(c.pt.x - static_cast<float>(x)), 1.0f);
    EXPECT_LE(std::abs(c.pt.y - static_cast<float>(y)), 1.0f);
    if (c.pt == cv::Point2f(static_cast<float>(x), static_cast<float>(y))) continue;
    ++moved;
    EXPECT_NEAR(c.response, SegmentTestScore(image, x, y), 0.5 * SegmentTestScore(image, x, y)) << c.pt;
  }
  EXPECT_GT(moved, corners / 2);
  EXPECT_GT(border, 0);
}

// Every corner cv::FAST keeps after its suppression is kept, and every kept
// corner scores at least as much as each of its 8 neighbours.
TEST(DetectSegmentTestCorners, KeepsTheLocalMaximaOfTheScoreWithTheirPlateaus) {
  const cv::Mat image = TexturedImage(5);
  std::vector<cv::KeyPoint> fast;
  cv::FAST(image, fast, 15, /*nonmaxSuppression=*/true, cv::FastFeatureDetector::TYPE_9_16);
  SegmentTestScoreMap scores(image);
  const std::vector<cv::KeyPoint> corners = DetectSegmentTestCorners(15, &scores);
  std::set<std::pair<int, int>> kept;
  for (const cv::KeyPoint& c : corners) {
    const int x = static_cast<int>(c.pt.x), y = static_cast<int>(c.pt.y);
    kept.insert({x, y});
    EXPECT_EQ(c.response, static_cast<float>(SegmentTestScore(image, x, y)));
    EXPECT_EQ(c.size, kBriskKeypointSizePx);
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const int nx = x + dx, ny = y + dy;  // the score is defined 3 px inside the image
        if (nx < 3 || ny < 3 || nx >= image.cols - 3 || ny >= image.rows - 3) continue;
        const int n = SegmentTestScore(image, nx, ny);
        if (n >= 15) {
          EXPECT_LE(static_cast<float>(n), c.response) << c.pt;
        }
      }
    }
  }
  for (const cv::KeyPoint& c : fast) {
    EXPECT_TRUE(kept.count({static_cast<int>(c.pt.x), static_cast<int>(c.pt.y)})) << c.pt;
  }
  EXPECT_GT(corners.size(), fast.size());
}

// Random 64-byte descriptors; a few rows repeated so that ties occur.
cv::Mat RandomDescriptors(int rows, std::mt19937* rng) {
  cv::Mat d(rows, 64, CV_8U);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < 64; ++c) d.at<std::uint8_t>(r, c) = static_cast<std::uint8_t>(byte(*rng));
  }
  for (int r = 3; r < rows; r += 7) d.row(r - 3).copyTo(d.row(r));
  return d;
}

// Near copies of some train rows, so that matches exist.
cv::Mat NoisyCopies(const cv::Mat& train, int rows, std::mt19937* rng) {
  cv::Mat q = RandomDescriptors(rows, rng);
  std::uniform_int_distribution<int> bit(0, 511);
  for (int r = 0; r < rows; r += 2) {
    train.row(r).copyTo(q.row(r));
    for (int k = 0; k < 20; ++k) {
      const int b = bit(*rng);
      q.at<std::uint8_t>(r, b / 8) ^= static_cast<std::uint8_t>(1 << (b % 8));
    }
  }
  return q;
}

TEST(MatchMutualNearest, AllPairsEqualsBfMatcherWithCrossCheck) {
  std::mt19937 rng(7);
  const cv::Mat train = RandomDescriptors(90, &rng);
  const cv::Mat query = NoisyCopies(train, 60, &rng);
  for (int max_bits : {40, 90, 512}) {
    std::vector<cv::DMatch> expected;
    cv::BFMatcher(cv::NORM_HAMMING, /*crossCheck=*/true).match(query, train, expected);
    expected.erase(std::remove_if(expected.begin(), expected.end(),
                                  [&](const cv::DMatch& m) { return m.distance > static_cast<float>(max_bits); }),
                   expected.end());
    const std::vector<cv::DMatch> matches = MatchMutualNearest(query, train, max_bits);
    ASSERT_EQ(matches.size(), expected.size()) << max_bits;
    ASSERT_GT(matches.size(), 10u);
    for (size_t i = 0; i < matches.size(); ++i) {
      EXPECT_EQ(matches[i].queryIdx, expected[i].queryIdx);
      EXPECT_EQ(matches[i].trainIdx, expected[i].trainIdx);
      EXPECT_EQ(matches[i].distance, expected[i].distance);
    }
  }
}

TEST(MatchMutualNearest, CandidatesRestrictBothSidesOfTheCheck) {
  std::mt19937 rng(11);
  const cv::Mat train = RandomDescriptors(80, &rng);
  const cv::Mat query = NoisyCopies(train, 50, &rng);
  MatchCandidates candidates(static_cast<size_t>(query.rows));
  std::bernoulli_distribution admit(0.3);
  for (int q = 0; q < query.rows; ++q) {
    for (int t = 0; t < train.rows; ++t) {
      if (admit(rng) || t == q) candidates[static_cast<size_t>(q)].push_back(t);
    }
  }
  // Brute force over the admissible pairs only.
  auto admissible = [&](int q, int t) {
    const auto& list = candidates[static_cast<size_t>(q)];
    return std::find(list.begin(), list.end(), t) != list.end();
  };
  auto distance = [&](int q, int t) { return cv::norm(query.row(q), train.row(t), cv::NORM_HAMMING); };
  std::vector<std::pair<int, int>> expected;
  for (int q = 0; q < query.rows; ++q) {
    int best_t = -1;
    for (int t = 0; t < train.rows; ++t) {
      if (admissible(q, t) && (best_t < 0 || distance(q, t) < distance(q, best_t))) best_t = t;
    }
    if (best_t < 0) continue;
    int best_q = -1;
    for (int p = 0; p < query.rows; ++p) {
      if (admissible(p, best_t) && (best_q < 0 || distance(p, best_t) < distance(best_q, best_t))) best_q = p;
    }
    if (best_q == q && distance(q, best_t) <= 90) expected.emplace_back(q, best_t);
  }
  std::vector<std::pair<int, int>> got;
  for (const cv::DMatch& m : MatchMutualNearest(query, train, 90, &candidates)) got.emplace_back(m.queryIdx, m.trainIdx);
  EXPECT_EQ(got, expected);
  EXPECT_GT(got.size(), 10u);
  // Without the restriction the answer differs (the test can fail).
  std::vector<std::pair<int, int>> all;
  for (const cv::DMatch& m : MatchMutualNearest(query, train, 90)) all.emplace_back(m.queryIdx, m.trainIdx);
  EXPECT_NE(all, expected);
}

TEST(MatchMutualNearest, EmptySidesGiveNoMatches) {
  std::mt19937 rng(3);
  const cv::Mat d = RandomDescriptors(5, &rng);
  EXPECT_TRUE(MatchMutualNearest(cv::Mat(), d, 90).empty());
  EXPECT_TRUE(MatchMutualNearest(d, cv::Mat(), 90).empty());
  const MatchCandidates none(5);
  EXPECT_TRUE(MatchMutualNearest(d, d, 512, &none).empty());
}

}  // namespace
}  // namespace vio::frontend
