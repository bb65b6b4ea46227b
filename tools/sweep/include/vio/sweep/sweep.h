#pragma once
// `vio sweep`: every combination dataset x policy x window size as its own
// `vio run` process, N at a time, then one table (CSV and Markdown) and plots.
//
// Output folder:
//   runs/<dataset>/<policy>_<window>/   one `vio run` output folder each, plus
//       run.log   the run's stdout and stderr
//       done      the marker "exit_code=<n>", written (temp name + rename) after
//                 the process exited and left a summary.json; a folder without
//                 it is an unfinished run and is redone from scratch
//   results.csv, results.md             one row per run
//   jobs.txt                            (--emit_jobs) one shell line per run
//   plots/                              PNGs (plot_sweep.py) and the data behind them
//
// Monte Carlo (seeds > 0): the datasets are `seeds` simulations of one
// experiment that differ in their measurement noise only,
//   datasets/seed_<k>/   `vio simulate --noise_seed=k SIMULATE_FLAGS` (k = 1..seeds;
//                        a `done` marker as for runs: an unfinished one is redone)
// every run writes its covariance (--output_covariance) and NEES, results.md
// gets a table per configuration over the seeds (mean ATE, ANEES with its 95%
// chi-square bounds) and plots/nees.png the NEES over time per configuration.
//
// A run that exits without a summary.json (unknown policy, bad flag, crash,
// kill) is "failed" and is retried by the next sweep; a run that wrote its
// summary (status ok, diverged or not_initialized) is finished and kept.
#include <functional>
#include <iosfwd>
#include <limits>
#include <string>
#include <vector>

namespace vio::tools {

/// One explicit run of a sweep: policy, window and local map.
struct SweepCombination {
  std::string policy;
  int window_size = 0;
  int local_map_keyframes = 0;  ///< passed as --local_map_keyframes when > 0
};

/// What to sweep and how.
struct SweepRequest {
  std::vector<std::string> datasets;  ///< EuRoC ASL folders (holding mav0/)
  std::vector<std::string> policies;  ///< passed as --policy
  std::vector<int> window_sizes;      ///< passed as --window_size [frames]
  /// Explicit runs; when not empty they replace the policies x window_sizes product.
  std::vector<SweepCombination> combinations;
  std::string output_dir;             ///< the sweep's folder (created when missing)
  std::string vio_binary;             ///< the `vio` executable every run uses
  std::string config_path;            ///< --config of every run; empty = none
  std::vector<std::string> run_flags; ///< further `vio run` flags, e.g. "--init=groundtruth"
  int jobs = 1;                       ///< runs at a time
  int seeds = 0;                      ///< Monte Carlo realizations (noise seeds); 0 = the datasets as given
  std::vector<std::string> simulate_flags;  ///< `vio simulate` flags of the Monte Carlo datasets
  /// Asked while runs go: a signal number (SIGINT, SIGTERM) stops the sweep: no further run starts,
  /// the running ones get the signal (they stop and write what they estimated) and are waited for.
  /// Empty: never.
  std::function<int()> stop_signal;
};

/// Exit codes of a run stopped by SIGINT or SIGTERM (128 + signal): it wrote its summary (status
/// interrupted) but is not finished: no `done` marker, the next sweep redoes it.
inline bool IsInterruptedExitCode(int exit_code) { return exit_code == 130 || exit_code == 143; }

/// One combination of the sweep.
struct SweepRun {
  std::string dataset_name;  ///< the dataset folder's name
  std::string dataset_dir;   ///< absolute
  std::string policy;
  int window_size = 0;
  int local_map_keyframes = 0;  ///< --local_map_keyframes of the run; 0 = not set by the sweep
  std::string run_dir;  ///< <output_dir>/runs/<dataset_name>/<PolicyLabel>_<window_size>
  std::string Label() const;  ///< "<dataset_name> <PolicyLabel>_<window_size>"
  /// The policy, with "+map<K>" when the run has a local map of K keyframes.
  std::string PolicyLabel() const;
};

/// RPE over one sub-trajectory length, as summary.json reports it.
struct SweepRpe {
  double length_m = 0;       ///< [m]
  double trans_pct = 0;      ///< mean translation error [% of length]
  double rot_deg_per_m = 0;  ///< mean rotation error [deg/m]
};

/// The outcome of one run. Numbers are NaN when the run did not report them.
struct SweepResult {
  static constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  SweepRun run;
  /// ok | diverged | not_initialized (summary.json's status), failed (the
  /// process ended without a summary.json, or it is malformed), missing (not
  /// run yet: no `done` marker), interrupted (stopped by a signal; redone by
  /// the next sweep).
  std::string status = "missing";
  int exit_code = -1;              ///< of `vio run`; -1 when unknown
  std::string message;             ///< why it is not ok (e.g. the last line of run.log)
  bool reused = false;             ///< finished by an earlier sweep, not rerun
  double ate_rmse_m = kNaN;        ///< ATE RMSE after posyaw alignment [m]
  std::vector<SweepRpe> rpe;
  double ms_per_frame = kNaN;      ///< [ms]
  double real_time_factor = kNaN;  ///< dataset duration / processing time
  double peak_memory_mb = kNaN;    ///< peak resident memory of the run [MB]
  double nees_pose = kNaN;         ///< mean pose NEES over the run's frames (6 dof)
  double nees_position = kNaN;     ///< mean position NEES (3 dof)
  double nees_orientation = kNaN;  ///< mean orientation NEES (3 dof)
  double time_offset_ms = kNaN;        ///< summary.json's calibration.time_offset_ms [ms]
  double time_offset_sigma_ms = kNaN;  ///< its sigma, when the run estimated it [ms]
  double true_time_offset_ms = kNaN;   ///< the dataset's mav0/rig_truth.yaml (vio simulate), when it has one [ms]
  bool Ok() const { return status == "ok"; }
};

/// The combinations in order (dataset, then policy, then window size).
/// Throws std::invalid_argument for an empty list, a dataset that is not a
/// folder, two datasets with the same folder name or a window size < 1.
std::vector<SweepRun> PlanSweep(const SweepRequest& request);

/// argv of one `vio run` (argv[0] = request.vio_binary). Throws
/// std::invalid_argument when run_flags set what the sweep sets
/// (--dataset, --output_dir, --policy, --window_size, --config).
std::vector<std::string> RunArguments(const SweepRequest& request, const SweepRun& run);

/// One POSIX shell line that does the run exactly as the sweep does: skip it
/// when `done` exists, else clear the folder, run, write `done`. Exits with
/// the run's exit code.
std::string JobCommand(const SweepRequest& request, const SweepRun& run);

/// `s` quoted for a POSIX shell ('...').
std::string ShellQuote(const std::string& s);

/// Splits a flag string on blanks; '...' and "..." group (quotes removed).
/// Throws std::invalid_argument on an unterminated quote.
std::vector<std::string> SplitFlags(const std::string& text);

/// True when the run folder holds the `done` marker.
bool IsRunFinished(const SweepRun& run);

/// The result of a run folder: its marker and summary.json; status "missing"
/// without a marker, "failed" with a malformed summary.json.
SweepResult ReadRunResult(const SweepRun& run);

/// Runs one combination now (clears its folder, forks `vio run`, waits,
/// writes the marker) and reads its result.
SweepResult ExecuteRun(const SweepRequest& request, const SweepRun& run);

/// Runs every unfinished combination, request.jobs at a time, and reuses the
/// finished ones. Writes one progress line per run to `progress`. Results in
/// plan order. A stop request (request.stop_signal) ends it early: the runs
/// not started are "missing", the stopped ones "interrupted".
std::vector<SweepResult> RunSweep(const SweepRequest& request, std::ostream& progress);

/// Reads every combination's folder (nothing is run).
std::vector<SweepResult> CollectSweep(const SweepRequest& request);

/// "[3/20] V2_01 swf_10 ok ATE 0.020 m 6.1 ms/frame" and the like.
std::string ProgressLine(const SweepResult& result, int index, int total);

/// results.csv: a header line, then one row per run (RPE columns for every
/// length any run reports). NaN and absent values are empty fields.
std::string ResultsCsv(const std::vector<SweepResult>& results);
/// results.md: a Markdown table, one row per run.
std::string ResultsMarkdown(const std::vector<SweepResult>& results);

/// Monte Carlo: simulates the seed datasets that are not finished (one `vio
/// simulate` process each, request.jobs at a time is not needed: they are
/// short) and returns their folders, seed_01.. in order. Throws
/// std::runtime_error naming the log of a simulation that failed.
std::vector<std::string> SimulateSeedDatasets(const SweepRequest& request, std::ostream& progress);

/// One configuration (policy, window) over the Monte Carlo runs.
struct MonteCarloSummary {
  std::string policy;
  int window_size = 0;
  int runs = 0;                    ///< runs with NEES (status ok)
  double mean_ate_m = 0;           ///< mean over runs of the ATE RMSE [m]
  double anees_pose = 0;           ///< mean pose NEES over runs and frames (6 dof)
  double anees_position = 0;       ///< (3 dof)
  double anees_orientation = 0;    ///< (3 dof)
  double lower_pose = 0;           ///< 95% bounds of the mean over `runs` runs at one instant, 6 dof
  double upper_pose = 0;
  double fraction_in_bounds = 0;   ///< frames seen by every run whose run-mean pose NEES is within the bounds
  /// Per frame seen by every run: time from the first such frame [s] and the run-mean pose NEES.
  std::vector<std::pair<double, double>> nees_over_time;
  /// The estimated camera-IMU time offset against the dataset's truth, over the ok runs that have an
  /// estimate, its sigma and a true offset (final estimates, one per run).
  int offset_runs = 0;
  double offset_mean_error_ms = 0;  ///< mean of estimate - truth [ms]
  double offset_rms_error_ms = 0;   ///< [ms]
  double offset_mean_sigma_ms = 0;  ///< [ms]
  double anees_time_offset = 0;     ///< mean of ((estimate - truth) / sigma)^2 (1 dof)
  double lower_time_offset = 0;     ///< 95% bounds of that mean over offset_runs runs, chi2(N)/N
  double upper_time_offset = 0;
};

/// Groups the results by (policy, window) and reads each ok run's nees.csv.
std::vector<MonteCarloSummary> SummarizeMonteCarlo(const std::vector<SweepResult>& results);

/// The Markdown table of SummarizeMonteCarlo, and a second one of the time offset when a
/// configuration has runs with a true offset.
std::string MonteCarloMarkdown(const std::vector<MonteCarloSummary>& summaries);

/// Writes jobs.txt (one JobCommand per line, plan order); returns its path.
std::string WriteJobsFile(const SweepRequest& request);

/// Writes results.csv and results.md into request.output_dir.
void WriteResults(const SweepRequest& request, const std::vector<SweepResult>& results);

/// Writes the plot data (aligned trajectories, errors over time) under
/// <output_dir>/plots/data and runs `python plot_script` on it. Returns a
/// one-line report ("plots in DIR/plots: ..." or why there are none); plots
/// are optional and never throw for a missing Python or script.
std::string MakePlots(const SweepRequest& request, const std::vector<SweepResult>& results,
                      const std::string& python, const std::string& plot_script);

/// tools/plot_sweep.py of this source tree ($VIO_SOURCE_DIR, the compiled-in
/// source folder, then next to the binary); empty when none exists.
std::string FindPlotScript(const std::string& vio_binary);

/// One summary paragraph (counts, failed runs by name, output files).
std::string SweepSummary(const SweepRequest& request, const std::vector<SweepResult>& results);

}  // namespace vio::tools
