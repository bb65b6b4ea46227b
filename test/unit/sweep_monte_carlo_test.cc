// `vio sweep --seeds`: ANEES of a configuration over its runs, the NEES over
// time of the frames every run has, the share within the 95% bounds, and the
// Markdown table.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/evaluation/nees.h"
#include "vio/sweep/sweep.h"

namespace vio::tools {
namespace {

using ::testing::HasSubstr;

// An ok run whose summary has the given mean NEES and whose nees.csv has
// pose NEES `values` at t = 1, 2, ... s.
// `shift_ns` moves every frame (a run's own time offset estimate moves its states).
SweepResult MonteCarloRun(const std::string& dataset, double ate_m, const std::vector<double>& values,
                          long long shift_ns = 0) {
  SweepResult r;
  r.run.dataset_name = dataset;
  r.run.policy = "swf";
  r.run.window_size = 10;
  r.run.run_dir = test::MakeTempDir("monte_carlo") + "/" + dataset;
  std::filesystem::create_directories(r.run.run_dir);
  std::ofstream nees(r.run.run_dir + "/nees.csv");
  nees << "#t_ns,nees_position,nees_orientation,nees_pose\n";
  double sum = 0;
  for (size_t k = 0; k < values.size(); ++k) {
    nees << (k + 1) * 1'000'000'000LL + shift_ns << ",1,2," << values[k] << "\n";
    sum += values[k];
  }
  r.status = "ok";
  r.ate_rmse_m = ate_m;
  r.nees_pose = sum / static_cast<double>(values.size());
  r.nees_position = 1;
  r.nees_orientation = 2;
  return r;
}

TEST(SweepMonteCarlo, AneesOverRunsAndNeesOverTime) {
  std::vector<SweepResult> results = {MonteCarloRun("seed_01", 0.01, {2, 6, 30}),
                                      MonteCarloRun("seed_02", 0.03, {4, 6, 30, 8}, 400'000)};
  SweepResult failed;
  failed.run = results[0].run;
  failed.run.dataset_name = "seed_03";
  failed.status = "diverged";
  results.push_back(failed);

  const std::vector<MonteCarloSummary> summaries = SummarizeMonteCarlo(results);
  ASSERT_EQ(summaries.size(), 1u);
  const MonteCarloSummary& s = summaries[0];
  EXPECT_EQ(s.runs, 2);
  EXPECT_DOUBLE_EQ(s.mean_ate_m, 0.02);
  EXPECT_DOUBLE_EQ(s.anees_pose, (38.0 / 3 + 48.0 / 4) / 2);
  EXPECT_DOUBLE_EQ(s.anees_position, 1);
  const ChiSquareBounds bounds = AneesBounds95(6, 2);
  EXPECT_DOUBLE_EQ(s.lower_pose, bounds.lower);
  EXPECT_DOUBLE_EQ(s.upper_pose, bounds.upper);
  // Frames both runs have (0.4 ms apart: the same frames): t = 1, 2, 3 s -> 0, 1, 2 s; means 3, 6, 30.
  ASSERT_EQ(s.nees_over_time.size(), 3u);
  EXPECT_DOUBLE_EQ(s.nees_over_time[1].first, 1.0);
  EXPECT_DOUBLE_EQ(s.nees_over_time[0].second, 3.0);
  EXPECT_DOUBLE_EQ(s.nees_over_time[2].second, 30.0);
  EXPECT_DOUBLE_EQ(s.fraction_in_bounds, 2.0 / 3);  // 3 and 6 within [2.2, 11.7], 30 not

  const std::string md = MonteCarloMarkdown(summaries);
  EXPECT_THAT(md, HasSubstr("| swf | 10 | 2 | 0.0200 | 12.33 | ["));
  EXPECT_THAT(md, HasSubstr("| 67 % | 1.00 | 2.00 |"));
}

TEST(SweepMonteCarlo, TimeOffsetErrorAndNeesAgainstTheTrueOffset) {
  std::vector<SweepResult> results = {MonteCarloRun("seed_01", 0.01, {6}), MonteCarloRun("seed_02", 0.01, {6}),
                                      MonteCarloRun("seed_03", 0.01, {6})};
  const double estimates[] = {10.2, 9.6, 10.4};
  for (int k = 0; k < 3; ++k) {
    results[k].time_offset_ms = estimates[k];
    results[k].time_offset_sigma_ms = 0.2;
    results[k].true_time_offset_ms = 10.0;
  }
  results[2].time_offset_sigma_ms = SweepResult::kNaN;  // not estimated: not counted

  const std::vector<MonteCarloSummary> summaries = SummarizeMonteCarlo(results);
  ASSERT_EQ(summaries.size(), 1u);
  const MonteCarloSummary& s = summaries[0];
  EXPECT_EQ(s.offset_runs, 2);
  EXPECT_NEAR(s.offset_mean_error_ms, -0.1, 1e-12);
  EXPECT_NEAR(s.offset_rms_error_ms, std::sqrt((0.04 + 0.16) / 2), 1e-12);
  EXPECT_NEAR(s.anees_time_offset, (1.0 + 4.0) / 2, 1e-12);
  EXPECT_DOUBLE_EQ(s.upper_time_offset, AneesBounds95(1, 2).upper);
  EXPECT_THAT(MonteCarloMarkdown(summaries), HasSubstr("| swf | 10 | 2 | -0.100 | 0.316 | 0.200 | 2.50 | ["));

  for (SweepResult& r : results) r.true_time_offset_ms = SweepResult::kNaN;  // no truth: no offset table
  EXPECT_THAT(MonteCarloMarkdown(SummarizeMonteCarlo(results)), ::testing::Not(HasSubstr("time offset")));
}

}  // namespace
}  // namespace vio::tools
