// The equivalence theorems (4.3.1-4.3.5, Remark 4.3.2) on small nonlinear
// problems (SE3 poses on vio::PoseManifold, landmarks, rectified stereo via
// vio::StereoFactor, a constant-body-velocity motion) linearized at the same
// point for both forms, wrong variants that must fail, and `vio verify` end
// to end.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "vio/marginalization/kalman_reference.h"
#include "vio/verify/verify.h"

namespace vio::tools {
namespace {

using marginalization::CheckAll;
using marginalization::EquivalenceCheck;
using marginalization::EquivalenceProblems;

constexpr double kTolerance = 1e-8;

class NonlinearTheorems : public testing::TestWithParam<unsigned> {};

TEST_P(NonlinearTheorems, FilterAndOptimizationFormsAgreeAtTheSameLinearizationPoint) {
  for (const NonlinearProblemSizes& sizes :
       {NonlinearProblemSizes{6, 4}, NonlinearProblemSizes{1, 2}, NonlinearProblemSizes{15, 6}}) {
    const std::vector<EquivalenceCheck> checks = CheckAll(RandomNonlinearProblems(sizes, GetParam()));
    ASSERT_EQ(checks.size(), 6u);
    for (const EquivalenceCheck& check : checks) {
      EXPECT_LT(check.deviation.mean, kTolerance) << check.theorem << ": " << check.description;
      EXPECT_LT(check.deviation.covariance, kTolerance) << check.theorem << ": " << check.description;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Seeds, NonlinearTheorems, testing::Values(1u, 2u, 3u, 4u, 5u, 6u));

TEST(NonlinearProblems, AreGenuinelyNonlinearAndNoisy) {
  const EquivalenceProblems problems = RandomNonlinearProblems({6, 4}, 3);
  // Pose blocks: 7 ambient, 6 tangent, unit quaternions.
  const auto& ekf = problems.ekf_update;
  ASSERT_EQ(ekf.layout.AmbientSize(), 10 + 18);
  ASSERT_EQ(ekf.layout.TangentSize(), 9 + 18);
  EXPECT_NEAR(ekf.state.mean.segment<4>(3).norm(), 1.0, 1e-12);
  // Pixel noise and the state's error give innovations of pixels.
  EXPECT_GT(ekf.measurements.innovation.norm(), 1.0);
  // At (μ_x, ℓ(μ_x, z)) the new features are exactly observed.
  EXPECT_LT(problems.ekf_augmentation.measurements.innovation.norm(), 1e-9);
  // The motion rotates the state: G is not the identity, and the cost side's
  // Jacobian (autodiff) equals -G (analytic).
  const auto& propagation = problems.ekf_propagation;
  EXPECT_GT((propagation.dynamics.G - Eigen::MatrixXd::Identity(9, 9)).norm(), 1e-2);
  EXPECT_LT((propagation.residual.J_from + propagation.dynamics.G).norm(), 1e-12);
  EXPECT_LT((propagation.residual.J_to - Eigen::MatrixXd::Identity(9, 9)).norm(), 1e-12);
  EXPECT_LT(propagation.residual.r0.norm(), 1e-12);
}

TEST(NonlinearProblems, SameSeedSameProblems) {
  const EquivalenceProblems a = RandomNonlinearProblems({5, 3}, 9);
  const EquivalenceProblems b = RandomNonlinearProblems({5, 3}, 9);
  EXPECT_EQ(a.msckf_update.measurements.H_x, b.msckf_update.measurements.H_x);
  EXPECT_EQ(a.ekf_update.state.mean, b.ekf_update.state.mean);
  const EquivalenceProblems c = RandomNonlinearProblems({5, 3}, 10);
  EXPECT_NE(a.ekf_update.state.mean, c.ekf_update.state.mean);
  EXPECT_THROW(RandomNonlinearProblems({0, 3}, 1), std::invalid_argument);
  EXPECT_THROW(RandomNonlinearProblems({5, 1}, 1), std::invalid_argument);
}

TEST(NonlinearNegativeControls, WrongFiltersDoNotAgree) {
  for (unsigned seed = 1; seed <= 4; ++seed) {
    const std::vector<EquivalenceCheck> controls =
        marginalization::NegativeControls(RandomNonlinearProblems({6, 4}, seed));
    ASSERT_EQ(controls.size(), 2u);
    for (const EquivalenceCheck& control : controls) {
      EXPECT_GT(std::max(control.deviation.mean, control.deviation.covariance), 10 * kTolerance)
          << control.description;
    }
  }
}

TEST(NonlinearNegativeControls, WrongModelJacobiansAreDetected) {
  EquivalenceProblems problems = RandomNonlinearProblems({6, 4}, 2);
  // A wrong inverse-measurement Jacobian (EKF augmentation) ...
  problems.ekf_augmentation.L_z(0, 0) *= 1.0 + 1e-5;
  EXPECT_GT(marginalization::CheckEkfAugmentation(problems.ekf_augmentation).deviation.covariance,
            kTolerance);
  // ... a motion Jacobian that forgets the rotation's effect on position ...
  problems.msckf_propagation.dynamics.G.block(0, 3, 3, 3).setZero();
  EXPECT_GT(marginalization::CheckMsckfPropagation(problems.msckf_propagation).deviation.covariance, 1e-3);
  // ... and an innovation off by half a pixel on the filter side only.
  marginalization::MsckfUpdateProblem moved = problems.msckf_update;
  moved.measurements.innovation.head(3) += Eigen::Vector3d(0.5, 0.5, 0.5);
  const marginalization::Gaussian filter =
      marginalization::MsckfFeatureUpdate(moved.state, moved.layout, moved.measurements);
  const marginalization::Gaussian optimization =
      marginalization::MsckfFeatureUpdateByMarginalization(problems.msckf_update);
  EXPECT_GT(marginalization::Compare(filter, optimization, moved.layout, moved.state.mean).mean, 1e-4);
}

TEST(RunVerification, ReportsEveryTheoremForBothKindsAndPasses) {
  VerifyOptions options;
  options.trials = 3;
  const VerifyReport report = RunVerification(options);
  EXPECT_TRUE(report.passed);
  ASSERT_EQ(report.rows.size(), 2u * 6u + 2u * 2u);
  int controls = 0;
  for (const VerifyRow& row : report.rows) {
    EXPECT_TRUE(row.passed) << row.theorem << " " << row.kind;
    controls += row.control ? 1 : 0;
  }
  EXPECT_EQ(controls, 4);
  EXPECT_EQ(report.rows.front().theorem, "4.3.1");
  EXPECT_FALSE(report.rows.front().control);
  EXPECT_TRUE(report.rows.back().control);
  const std::string text = FormatVerifyReport(report);
  EXPECT_NE(text.find("PASS"), std::string::npos) << text;
  EXPECT_NE(text.find("4.3.5    nonlinear"), std::string::npos) << text;
}

TEST(RunVerification, AToleranceBelowRoundOffFails) {
  VerifyOptions options;
  options.trials = 2;
  options.tolerance = 1e-300;  // nothing computed in floating point is that close
  const VerifyReport report = RunVerification(options);
  EXPECT_FALSE(report.passed);
  EXPECT_NE(FormatVerifyReport(report).find("FAIL"), std::string::npos);
  options.trials = 0;
  EXPECT_THROW(RunVerification(options), std::invalid_argument);
}

/// Exit status and stdout of `vio <args>`.
std::pair<int, std::string> RunVio(const std::string& args) {
  const std::string command = std::string(VIO_BINARY) + " " + args + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) throw std::runtime_error("cannot run " + command);
  std::string output;
  char buffer[4096];
  while (fgets(buffer, sizeof(buffer), pipe) != nullptr) output += buffer;
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, output};
}

TEST(VerifyCommand, PrintsTheTableAndExitsZero) {
  const auto [status, output] = RunVio("verify --trials=2 --seed=5 --num_landmarks=4 --num_poses=3");
  EXPECT_EQ(status, 0) << output;
  for (const char* theorem : {"4.3.1", "4.3.2", "4.3.3", "4.3.4", "4.3.5", "R4.3.2"}) {
    EXPECT_NE(output.find(theorem), std::string::npos) << theorem << "\n" << output;
  }
  EXPECT_NE(output.find("seeds 5..6"), std::string::npos) << output;
  EXPECT_NE(output.find("PASS"), std::string::npos) << output;
}

TEST(VerifyCommand, BadFlagsExitTwo) {
  EXPECT_EQ(RunVio("verify --num_poses=1").first, 2);
  EXPECT_EQ(RunVio("verify --trials=0").first, 2);
  EXPECT_EQ(RunVio("verify stray_argument").first, 2);
}

}  // namespace
}  // namespace vio::tools
