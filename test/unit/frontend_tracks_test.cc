// FeatureTracks (the two-way track/frame index) and FeatureGrid (bucketing).
#include <gtest/gtest.h>

#include "vio/frontend/feature_grid.h"
#include "vio/frontend/feature_tracks.h"

namespace vio::frontend {
namespace {

TEST(FeatureTracks, IssuesFreshIdsAndIndexesBothWays) {
  FeatureTracks tracks;
  const LandmarkId a = tracks.NewTrack(), b = tracks.NewTrack();
  EXPECT_NE(a, b);
  EXPECT_EQ(tracks.num_tracks(), 2);
  tracks.Observe(a, 0);
  tracks.Observe(b, 0);
  tracks.Observe(a, 1);
  tracks.Observe(a, 4);
  EXPECT_EQ(tracks.FramesOf(a), (std::vector<std::int64_t>{0, 1, 4}));
  EXPECT_EQ(tracks.FramesOf(b), (std::vector<std::int64_t>{0}));
  EXPECT_EQ(tracks.TracksIn(0), (std::vector<LandmarkId>{a, b}));
  EXPECT_EQ(tracks.TracksIn(4), (std::vector<LandmarkId>{a}));
  EXPECT_TRUE(tracks.TracksIn(2).empty());
  EXPECT_TRUE(tracks.FramesOf(LandmarkId(99)).empty());
  std::vector<int> lengths = tracks.TrackLengths();
  std::sort(lengths.begin(), lengths.end());
  EXPECT_EQ(lengths, (std::vector<int>{1, 3}));
}

TEST(FeatureTracks, StoresTheTrackPosition) {
  FeatureTracks tracks;
  const LandmarkId a = tracks.NewTrack();
  EXPECT_FALSE(tracks.Position(a));
  tracks.SetPosition(a, Eigen::Vector3d(1, 2, 3));
  EXPECT_EQ(*tracks.Position(a), Eigen::Vector3d(1, 2, 3));
}

TEST(FeatureTracksDeathTest, RejectsObservationsOutOfOrder) {
  FeatureTracks tracks;
  const LandmarkId a = tracks.NewTrack();
  tracks.Observe(a, 3);
  EXPECT_DEATH(tracks.Observe(a, 3), "out of order");
  EXPECT_DEATH(tracks.Observe(LandmarkId(42), 5), "never issued");
}

TEST(FeatureGrid, KeepsTheStrongestPerCell) {
  const FeatureGrid grid(100, 50, 50.0);
  EXPECT_EQ(grid.cols(), 2);
  EXPECT_EQ(grid.rows(), 1);
  EXPECT_EQ(grid.Cell({-5.0f, 200.0f}), 0);  // clamped
  EXPECT_EQ(grid.Cell({99.0f, 10.0f}), 1);
  std::vector<cv::KeyPoint> keypoints;
  const float responses[] = {5, 9, 1, 7, 3};
  const float xs[] = {10, 20, 30, 60, 70};
  for (int i = 0; i < 5; ++i) keypoints.emplace_back(cv::Point2f(xs[i], 10), 7.0f, -1, responses[i]);
  // Cell 0 holds 0 (5), 1 (9), 2 (1); cell 1 holds 3 (7), 4 (3): two per cell.
  EXPECT_EQ(grid.Bucket(keypoints, 2), (std::vector<int>{1, 3, 0, 4}));
  EXPECT_THROW(FeatureGrid(0, 10, 5.0), std::invalid_argument);
}

}  // namespace
}  // namespace vio::frontend
