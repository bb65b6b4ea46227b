// The ground truth of a front end's matches: scripted observations of points
// on the far wall of a room, exact pixels, with known continuations, a track
// that jumps to another point, re-acquisitions right and wrong, and a return
// under a new id.
#include <map>
#include <optional>
#include <vector>

#include <gtest/gtest.h>

#include "vio/estimator/stereo_geometry.h"
#include "vio/simulator/match_truth.h"

namespace vio::tools {
namespace {

constexpr Timestamp kStartNs = 1'000'000'000;
constexpr Timestamp kFrameNs = 100'000'000;

class MatchTruthTest : public ::testing::Test {
 protected:
  MatchTruthTest() {
    scene_.room = Eigen::AlignedBox3d(Eigen::Vector3d(-5, -5, 0), Eigen::Vector3d(5, 5, 4));
    scene_.boxes.emplace_back(Eigen::Vector3d(1, 0.8, 0), Eigen::Vector3d(2, 1.8, 1));
    // The camera looks along world +x (its x: world -y, its y: world -z).
    Eigen::Matrix3d R_w_c;
    R_w_c << 0, 0, 1, -1, 0, 0, 0, -1, 0;
    for (int k = -1; k <= kFrames; ++k) {
      GroundTruthState state;
      state.t_ns = kStartNs + k * kFrameNs;
      state.p_w_b = Eigen::Vector3d(-2.0, -0.5 + 0.1 * k, 1.0);
      state.q_w_b = Eigen::Quaterniond(R_w_c);
      groundtruth_.push_back(state);
    }
  }

  /// The exact observation of p_w with `id` in frame k.
  StereoObservation See(int k, std::int64_t id, const Eigen::Vector3d& p_w) const {
    const GroundTruthState& s = groundtruth_[static_cast<size_t>(k + 1)];
    const Eigen::Isometry3d T_w_cl = Eigen::Translation3d(s.p_w_b) * s.q_w_b * stereo_.T_b_cl;
    return {LandmarkId{id}, ProjectRectified(T_w_cl.inverse() * p_w, stereo_)};
  }

  static constexpr int kFrames = 6;
  Scene scene_;
  RectifiedStereo stereo_;
  std::vector<GroundTruthState> groundtruth_;
};

TEST_F(MatchTruthTest, CountsContinuationsReacquisitionsAndMissedReturns) {
  const Eigen::Vector3d a(5, 0.3, 1.2), b(5, -0.4, 0.8), c(5, 0.8, 1.5), d(5, -1.0, 2.0), e(5, 1.2, 0.6),
      f(5, -0.8, 1.6), g(5, 0.0, 2.2);
  std::vector<StereoFrame> frames(kFrames);
  for (int k = 0; k < kFrames; ++k) {
    StereoFrame& frame = frames[static_cast<size_t>(k)];
    frame.t_ns = kStartNs + k * kFrameNs;
    frame.observations.push_back(See(k, 1, a));                 // continues throughout: 5 correct
    frame.observations.push_back(See(k, 2, k < 3 ? b : c));     // jumps to c at frame 3: 2 correct, 3 wrong
    if (k < 2 || k == 4) frame.observations.push_back(See(k, 3, d));  // back at frame 4: reacquired, correct
    if (k < 2) frame.observations.push_back(See(k, 4, e));
    if (k == 4) frame.observations.push_back(See(k, 5, e));     // e again, under a new id: a missed return
    if (k < 2) frame.observations.push_back(See(k, 6, f));
    if (k == 4) frame.observations.push_back(See(k, 6, g));     // id 6 back on another point: reacquired, wrong
  }
  const MatchTruth truth = CheckMatches(scene_, stereo_, groundtruth_, frames, MatchTruthOptions{});
  EXPECT_EQ(truth.frames, kFrames);
  EXPECT_EQ(truth.unchecked, 0);
  EXPECT_EQ(truth.new_ids, 6);
  EXPECT_EQ(truth.continuing.correct, 5 + 2 + 1 + 1 + 1);
  EXPECT_EQ(truth.continuing.wrong, 3);
  EXPECT_EQ(truth.reacquired.correct, 1);
  EXPECT_EQ(truth.reacquired.wrong, 1);
  EXPECT_EQ(truth.missed_returns, 1);
  EXPECT_DOUBLE_EQ(truth.ReacquisitionRate(), 0.5);
  EXPECT_DOUBLE_EQ(truth.FalseReacquisitionRate(), 0.5);
}

// A pixel error below the tolerance is correct, above it wrong; a point the
// box hides is wrong even where it projects; no ground truth: unchecked.
TEST_F(MatchTruthTest, JudgesByTheToleranceTheOcclusionAndTheGroundTruthSpan) {
  const Eigen::Vector3d a(5, 0.3, 1.2);
  std::vector<StereoFrame> frames(3);
  for (int k = 0; k < 3; ++k) frames[static_cast<size_t>(k)].t_ns = kStartNs + k * kFrameNs;
  frames[0].observations.push_back(See(0, 1, a));
  StereoObservation near = See(1, 1, a);
  near.z_px += Eigen::Vector3d(2.0, 2.0, 0.0);  // 2 px off
  frames[1].observations.push_back(near);
  StereoObservation far = See(2, 1, a);
  far.z_px += Eigen::Vector3d(5.0, 5.0, 0.0);  // 5 px off
  frames[2].observations.push_back(far);
  MatchTruth truth = CheckMatches(scene_, stereo_, groundtruth_, frames, MatchTruthOptions{});
  EXPECT_EQ(truth.continuing.correct, 1);
  EXPECT_EQ(truth.continuing.wrong, 1);
  MatchTruthOptions loose;
  loose.max_error_px = 6.0;
  truth = CheckMatches(scene_, stereo_, groundtruth_, frames, loose);
  EXPECT_EQ(truth.continuing.correct, 2);

  // A wall point seen from frame 0's camera and hidden by the box from frame
  // 1's: at frame 1 its pixel sees the box, so the id is wrong there,
  // although the wall point projects onto that pixel exactly.
  auto visible = [&](int k, const Eigen::Vector3d& p_w) {
    const Eigen::Vector3d from = groundtruth_[static_cast<size_t>(k + 1)].p_w_b;
    return scene_.CastRay(from, (p_w - from).normalized()).t >= (p_w - from).norm() - 1e-9;
  };
  std::optional<Eigen::Vector3d> wall;
  for (double y = 0.0; y < 4.0 && !wall; y += 0.005) {
    const Eigen::Vector3d p(5.0, y, 0.5);
    if (visible(0, p) && !visible(1, p)) wall = p;
  }
  ASSERT_TRUE(wall.has_value());
  std::vector<StereoFrame> hidden = {{kStartNs, {See(0, 1, *wall)}}, {kStartNs + kFrameNs, {See(1, 1, *wall)}}};
  truth = CheckMatches(scene_, stereo_, groundtruth_, hidden, MatchTruthOptions{});
  EXPECT_EQ(truth.new_ids, 1);
  EXPECT_EQ(truth.continuing.wrong, 1);

  std::vector<StereoFrame> late = {{kStartNs + 100 * kFrameNs, {See(0, 1, a)}}};
  truth = CheckMatches(scene_, stereo_, groundtruth_, late, MatchTruthOptions{});
  EXPECT_EQ(truth.unchecked, 1);
  EXPECT_EQ(truth.new_ids, 0);
  MatchTruthOptions bad;
  bad.max_error_px = 0.0;
  EXPECT_THROW(CheckMatches(scene_, stereo_, groundtruth_, frames, bad), std::invalid_argument);
}

}  // namespace
}  // namespace vio::tools
