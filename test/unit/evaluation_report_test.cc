// Reports (JSON, text) and finding the ground truth a path names.
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/evaluation/trajectory_eval.h"

namespace vio::tools {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

std::vector<GroundTruthState> Line(int n) {
  std::vector<GroundTruthState> poses(n);
  for (int k = 0; k < n; ++k) {
    poses[k].t_ns = 1'403'715'274'302'142'000LL + k * 5'000'000LL;
    poses[k].p_w_b = Eigen::Vector3d(0.5 * k, 0.1 * k * k, 1.0);
    poses[k].q_w_b = Eigen::AngleAxisd(0.05 * k, Eigen::Vector3d::UnitZ());
  }
  return poses;
}

TrajectoryEvaluation KnownEvaluation() {
  TrajectoryEvaluation e;
  e.alignment = Alignment::kSe3;
  e.alignment_result.T_gt_est.translation() = Eigen::Vector3d(1.0, -2.0, 0.5);
  e.ate = AteResult{0.25, 0.2, 0.125, 0.75, 1.5, 100, 7};
  e.rpe = {RpeResult{1.0, 2.5, 0.375, 90}, ComputeRpe(AssociatedTrajectory{}, {10.0}).front()};
  return e;
}

TEST(EvalReport, JsonHasEveryFieldAndNullForMissingRpe) {
  const std::string json = ToJson(KnownEvaluation());
  EXPECT_THAT(json, HasSubstr("\"alignment\": \"se3\""));
  EXPECT_THAT(json, HasSubstr("\"T_gt_est\": {\"p_m\": [1, -2, 0.5], \"q_xyzw\": [0, 0, 0, 1]}"));
  EXPECT_THAT(json, HasSubstr("\"scale\": 1"));
  EXPECT_THAT(json, HasSubstr("\"ate\": {\"rmse_m\": 0.25, \"mean_m\": 0.2, \"median_m\": 0.125, "
                              "\"max_m\": 0.75, \"rot_rmse_deg\": 1.5, \"num_poses\": 100, "
                              "\"num_skipped\": 7}"));
  EXPECT_THAT(json, HasSubstr("{\"length_m\": 1, \"trans_pct\": 2.5, \"rot_deg_per_m\": 0.375, "
                              "\"num_pairs\": 90}"));
  EXPECT_THAT(json, HasSubstr("{\"length_m\": 10, \"trans_pct\": null, \"rot_deg_per_m\": null, "
                              "\"num_pairs\": 0}"));
  EXPECT_THAT(json, Not(HasSubstr("nan")));
  EXPECT_EQ(json.front(), '{');
  EXPECT_EQ(json.back(), '}');
}

TEST(EvalReport, TextNamesTheNumbersAndMarksMissingRpe) {
  const std::string text = ToText(KnownEvaluation());
  EXPECT_THAT(text, HasSubstr("alignment   se3"));
  EXPECT_THAT(text, HasSubstr("100 compared with the ground truth, 7 not (outside its time span"));
  EXPECT_THAT(text, HasSubstr("rmse 0.2500  mean 0.2000  median 0.1250  max 0.7500"));
  EXPECT_THAT(text, HasSubstr("rmse 1.500 deg"));
  EXPECT_THAT(text, HasSubstr("       1.0      2.500       0.3750     90"));
  EXPECT_THAT(text, HasSubstr("      10.0        n/a          n/a      0"));
}

class EvalGroundTruthPath : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = vio::test::MakeTempDir("eval_gt_path");
    gt_dir_ = dir_ + "/seq/mav0/state_groundtruth_estimate0";
    std::filesystem::create_directories(gt_dir_);
  }
  std::string dir_;
  std::string gt_dir_;
};

TEST_F(EvalGroundTruthPath, ReadsAslCsvFromASequenceFolderFirst) {
  WriteGroundTruthCsv(Line(5), gt_dir_ + "/data.csv");
  WriteTumTrajectory(Line(3), gt_dir_ + "/groundtruth_tum.txt");
  for (const std::string& path : {dir_ + "/seq", dir_ + "/seq/mav0", gt_dir_, gt_dir_ + "/data.csv"}) {
    EXPECT_EQ(ReadGroundTruthPath(path).size(), 5u) << path;
  }
  EXPECT_EQ(ReadGroundTruthPath(gt_dir_ + "/groundtruth_tum.txt").size(), 3u);
}

TEST_F(EvalGroundTruthPath, FallsBackToTumText) {
  WriteTumTrajectory(Line(3), gt_dir_ + "/groundtruth_tum.txt");
  const std::vector<GroundTruthState> gt = ReadGroundTruthPath(dir_ + "/seq");
  ASSERT_EQ(gt.size(), 3u);
  EXPECT_EQ(gt[2].t_ns, Line(3)[2].t_ns);
  EXPECT_LT((gt[2].p_w_b - Line(3)[2].p_w_b).norm(), 1e-9);
}

TEST_F(EvalGroundTruthPath, MissingGroundTruthNamesWhatWasLookedFor) {
  EXPECT_THROW(ReadGroundTruthPath(dir_ + "/nothing_here"), std::invalid_argument);
  try {
    ReadGroundTruthPath(dir_ + "/seq");
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_THAT(e.what(), HasSubstr("no ground truth in folder"));
    EXPECT_THAT(e.what(), HasSubstr("state_groundtruth_estimate0/groundtruth_tum.txt"));
  }
}

// The written-and-read round trip through TUM text (seconds) associates
// exactly with the ASL ground truth (nanoseconds).
TEST_F(EvalGroundTruthPath, TumEstimateAtGroundTruthStampsGivesZeroError) {
  WriteGroundTruthCsv(Line(40), gt_dir_ + "/data.csv");
  WriteTumTrajectory(Line(40), dir_ + "/estimate.txt");
  const TrajectoryEvaluation e =
      EvaluateTrajectory(ReadTumTrajectory(dir_ + "/estimate.txt"), ReadGroundTruthPath(dir_ + "/seq"));
  EXPECT_EQ(e.ate.num_poses, 40);
  EXPECT_EQ(e.ate.num_skipped, 0);
  EXPECT_LT(e.ate.rmse_m, 1e-9);
}

}  // namespace
}  // namespace vio::tools
