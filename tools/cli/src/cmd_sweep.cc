// `vio sweep`: every dataset x policy x window size as its own `vio run`
// process, then results.csv, results.md and plots (see vio/sweep/sweep.h).
#include <unistd.h>

#include <filesystem>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include <gflags/gflags.h>

#include "commands.h"
#include "vio/cli/stop_signal.h"
#include "vio/sweep/sweep.h"

DEFINE_string(datasets, "", "EuRoC ASL dataset folders, comma separated; a run is filed under the folder's name");
DEFINE_string(policies, "swf", "estimator policies to sweep, comma separated (passed as --policy)");
DEFINE_string(window_sizes, "10", "window sizes to sweep, comma separated (passed as --window_size) [frames]");
DEFINE_string(runs, "",
              "explicit policy:window pairs instead of --policies x --window_sizes, e.g. "
              "swf:5,swf:10,msckf:10,ekf:1,batch:10; policy:window:K also sets --local_map_keyframes=K "
              "(swf:10:8 runs as swf+map8_10)");
DEFINE_int32(seeds, 0,
             "Monte Carlo: simulate this many datasets that differ only in their noise (vio simulate "
             "--noise_seed=1..N with --simulate_flags) instead of --datasets; every run writes its covariance and "
             "NEES; results.md gets ANEES with 95% chi-square bounds, plots/nees.png the NEES over time");
DEFINE_string(simulate_flags, "",
              "with --seeds: `vio simulate` flags of the Monte Carlo datasets, e.g. \"--duration_s=20\" or "
              "\"--from=EUROC_DIR\"");
DEFINE_int32(jobs, 1, "runs at a time (each run is its own process)");
DEFINE_string(extra_flags, "", "further `vio run` flags for every run, e.g. \"--init=groundtruth --max_iterations=5\"");
DEFINE_bool(emit_jobs, false, "only write OUTPUT_DIR/jobs.txt, one shell line per run (GNU parallel, Slurm, k8s)");
DEFINE_bool(collect_only, false, "run nothing: build the table, plots and report from the run folders there are");
DEFINE_string(vio_binary, "", "the vio executable the runs use; empty = this one");
DEFINE_bool(plots, true, "draw the plots and write report.md (needs Python 3 with numpy and matplotlib)");
DEFINE_string(python, "/usr/bin/python3", "the Python 3 (with numpy and matplotlib) that draws the plots");
DEFINE_string(plot_script, "", "tools/plot_sweep.py; empty = the one of this source tree");
DECLARE_string(config);

namespace vio::tools {
namespace {

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!item.empty()) items.push_back(item);
  }
  return items;
}

std::vector<int> ParseWindowSizes(const std::string& text) {
  std::vector<int> sizes;
  for (const std::string& item : SplitList(text)) {
    size_t used = 0;
    int value = 0;
    try {
      value = std::stoi(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size()) {
      throw std::invalid_argument("--window_sizes: '" + item + "' is not an integer");
    }
    sizes.push_back(value);
  }
  return sizes;
}

// "swf:10,msckf:10:8" -> {(swf, 10, 0), (msckf, 10, 8)}: policy:window[:local map keyframes].
std::vector<SweepCombination> ParseRuns(const std::string& text) {
  std::vector<SweepCombination> runs;
  for (const std::string& item : SplitList(text)) {
    const size_t colon = item.find(':');
    if (colon == std::string::npos || colon == 0) {
      throw std::invalid_argument("--runs: '" + item + "' is not policy:window");
    }
    const size_t second = item.find(':', colon + 1);
    const std::vector<int> window = ParseWindowSizes(item.substr(colon + 1, second - colon - 1));
    if (window.size() != 1) throw std::invalid_argument("--runs: '" + item + "' is not policy:window");
    int keyframes = 0;
    if (second != std::string::npos) {
      const std::vector<int> k = ParseWindowSizes(item.substr(second + 1));
      if (k.size() != 1) throw std::invalid_argument("--runs: '" + item + "' is not policy:window:K");
      keyframes = k.front();
    }
    runs.push_back({item.substr(0, colon), window.front(), keyframes});
  }
  return runs;
}

std::string ThisBinary() {
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot find the vio executable (/proc/self/exe); give --vio_binary");
  return self.string();
}

// Run options given to `vio sweep` itself (e.g. --init=groundtruth) go to
// every run; --policy and --window_size are what the sweep varies.
std::vector<std::string> ForwardedOptionFlags() {
  std::vector<gflags::CommandLineFlagInfo> flags;
  gflags::GetAllFlags(&flags);
  std::vector<std::string> forwarded;
  for (const auto& f : flags) {
    if (f.is_default || f.filename.rfind("options/", 0) != 0) continue;
    if (f.name == "policy" || f.name == "window_size") {
      throw std::invalid_argument("--" + f.name + ": use --policies / --window_sizes in a sweep");
    }
    forwarded.push_back("--" + f.name + "=" + f.current_value);
  }
  return forwarded;
}

SweepRequest SweepRequestFromFlags(const std::vector<std::string>& args) {
  if (!args.empty()) throw std::invalid_argument("unexpected argument '" + args.front() + "'");
  if (FLAGS_output_dir.empty()) throw std::invalid_argument("--output_dir is required");
  SweepRequest request;
  request.datasets = SplitList(FLAGS_datasets);
  request.policies = SplitList(FLAGS_policies);
  request.window_sizes = ParseWindowSizes(FLAGS_window_sizes);
  request.combinations = ParseRuns(FLAGS_runs);
  request.output_dir = FLAGS_output_dir;
  request.vio_binary = FLAGS_vio_binary.empty() ? ThisBinary() : FLAGS_vio_binary;
  request.config_path = FLAGS_config;
  request.run_flags = ForwardedOptionFlags();
  for (const std::string& flag : SplitFlags(FLAGS_extra_flags)) request.run_flags.push_back(flag);
  request.jobs = FLAGS_jobs;
  if (request.jobs < 1) throw std::invalid_argument("--jobs must be >= 1");
  request.seeds = FLAGS_seeds;
  if (request.seeds < 0) throw std::invalid_argument("--seeds must be >= 0");
  request.simulate_flags = SplitFlags(FLAGS_simulate_flags);
  if (request.seeds > 0) {
    if (!request.datasets.empty()) throw std::invalid_argument("--seeds simulates its datasets: drop --datasets");
    for (const std::string& flag : request.simulate_flags) {
      if (flag.rfind("--output_dir", 0) == 0 || flag.rfind("--noise_seed", 0) == 0) {
        throw std::invalid_argument("--simulate_flags: '" + flag + "' is set by the sweep for every seed");
      }
    }
    for (const std::string& flag : request.run_flags) {
      if (flag.rfind("--trajectory=smoothed", 0) == 0) {
        throw std::invalid_argument("--seeds computes the NEES of the online estimates: '" + flag +
                                    "' cannot be evaluated with their covariances");
      }
    }
    request.run_flags.push_back("--output_covariance=true");
    request.datasets = SimulateSeedDatasets(request, std::cout);
  } else if (!request.simulate_flags.empty()) {
    throw std::invalid_argument("--simulate_flags needs --seeds");
  }
  if (!request.config_path.empty() && !std::filesystem::is_regular_file(request.config_path)) {
    throw std::invalid_argument("--config: file not found: " + request.config_path);
  }
  RunArguments(request, PlanSweep(request).front());  // checks datasets, names and run flags
  return request;
}

void PrintJobsHelp(const std::string& jobs_path, size_t num_jobs) {
  std::cout << "wrote " << num_jobs << " jobs to " << jobs_path
            << " (one shell line per run; a finished run is skipped)\n"
            << "  GNU parallel: parallel -j 4 < " << jobs_path << "\n"
            << "  Slurm:        sbatch --array=1-" << num_jobs << " --wrap='sed -n \"${SLURM_ARRAY_TASK_ID}p\" "
            << jobs_path << " | bash'\n"
            << "then the same `vio sweep` command with --collect_only builds results and plots\n";
}

int Sweep(const SweepRequest& request) {
  std::vector<SweepResult> results;
  if (FLAGS_collect_only) {
    results = CollectSweep(request);
    for (size_t i = 0; i < results.size(); ++i) {
      std::cout << ProgressLine(results[i], static_cast<int>(i + 1), static_cast<int>(results.size())) << "\n";
    }
  } else {
    results = RunSweep(request, std::cout);
  }
  if (const int signal = StopSignal()) {
    std::cout << "sweep stopped by a signal: the stopped and unstarted runs have no `done` marker; the same "
                 "command resumes the sweep (results and plots are not written)"
              << std::endl;
    return InterruptedExitCode(signal);
  }
  WriteResults(request, results);
  if (FLAGS_plots) {
    const std::string script = FLAGS_plot_script.empty() ? FindPlotScript(request.vio_binary) : FLAGS_plot_script;
    std::cout << MakePlots(request, results, FLAGS_python, script) << "\n";
  }
  std::cout << SweepSummary(request, results) << std::endl;
  for (const SweepResult& r : results) {
    if (!r.Ok()) return 1;
  }
  return 0;
}

}  // namespace

int SweepMain(const std::vector<std::string>& args) {
  SweepRequest request;
  try {
    request = SweepRequestFromFlags(args);
  } catch (const std::invalid_argument& e) {
    std::cerr << "vio sweep: " << e.what() << "\n(see vio sweep --help)\n";
    return 2;
  }
  if (FLAGS_emit_jobs) {
    const std::string path = WriteJobsFile(request);
    PrintJobsHelp(path, PlanSweep(request).size());
    return 0;
  }
  InstallStopSignalHandlers();
  request.stop_signal = &StopSignal;
  return Sweep(request);
}

}  // namespace vio::tools
