// A frame's feature rows to its stereo observations (stereo_frames.h): the one-frame path the run
// streams gives what the whole-file path gives, in id order, whatever the rows' order, and a
// repeated row replaces the earlier one.
#include "vio/dataset/stereo_frames.h"

#include <algorithm>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "euroc_calibration.h"
#include "vio/frontend/stereo_rectifier.h"

namespace vio::tools {
namespace {

constexpr Timestamp kT = 1'000'000'000;

// Rows of one frame: both cameras' pixels of 40 features near the image centre (the right one
// 20-60 px to the left), some seen by one camera only; feature ids out of order. No epipolar gate
// (1000 px): every pair with both pixels counts.
std::vector<FeatureObservation> Rows() {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-150.0, 150.0);
  std::uniform_real_distribution<double> disparity(20.0, 60.0);
  std::vector<FeatureObservation> rows;
  for (int k = 0; k < 40; ++k) {
    const std::int64_t id = (k * 17) % 41;
    const Eigen::Vector2d left(376.0 + u(rng), 240.0 + 0.5 * u(rng));
    if (k % 7 != 3) rows.push_back({kT, 0, id, left});
    if (k % 11 != 5) rows.push_back({kT, 1, id, left - Eigen::Vector2d(disparity(rng), 0.0)});
  }
  return rows;
}

void ExpectSameFrame(const StereoFrame& actual, const StereoFrame& expected) {
  ASSERT_EQ(actual.observations.size(), expected.observations.size());
  for (size_t k = 0; k < expected.observations.size(); ++k) {
    EXPECT_EQ(actual.observations[k].landmark, expected.observations[k].landmark) << k;
    EXPECT_EQ(actual.observations[k].z_px, expected.observations[k].z_px) << k;
  }
}

TEST(StereoFrames, OneFrameMatchesTheWholeFilePathWhateverTheRowOrder) {
  const frontend::StereoRectifier rectifier(test::EurocCamera(0), test::EurocCamera(1));
  std::vector<FeatureObservation> rows = Rows();
  rows.push_back(rows[4]);  // a repeated row: the later one counts
  rows.back().uv_px += Eigen::Vector2d(0.5, 0.25);
  StereoFramesReport whole_report;
  const std::vector<StereoFrame> whole = StereoFramesFromFeatures(rows, {{kT, ""}}, rectifier, 1000.0, &whole_report);
  ASSERT_EQ(whole.size(), 1u);
  EXPECT_GT(whole[0].observations.size(), 20u);
  EXPECT_TRUE(std::is_sorted(whole[0].observations.begin(), whole[0].observations.end(),
                             [](const StereoObservation& a, const StereoObservation& b) { return a.landmark < b.landmark; }));
  for (int order = 0; order < 3; ++order) {
    if (order == 1) std::reverse(rows.begin(), rows.end() - 1);  // the repeated row stays last
    if (order == 2) std::shuffle(rows.begin(), rows.end() - 1, std::mt19937(11));
    StereoFramesReport report;
    const StereoFrame frame = StereoFrameFromFeatures(kT, rows, rectifier, 1000.0, &report);
    ExpectSameFrame(frame, whole[0]);
    EXPECT_EQ(report.stereo_observations, whole_report.stereo_observations);
    EXPECT_EQ(report.left_only, whole_report.left_only);
    EXPECT_EQ(report.right_only, whole_report.right_only);
  }
}

}  // namespace
}  // namespace vio::tools
