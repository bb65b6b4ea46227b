// `vio sweep --seeds=N`: the Monte Carlo datasets and the consistency
// (NEES) of each configuration over them (sweep.h).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include "internal.h"
#include "vio/evaluation/nees.h"
#include "vio/sweep/sweep.h"

namespace vio::tools {
namespace {

namespace fs = std::filesystem;

std::string SeedName(int seed) {
  char name[32];
  std::snprintf(name, sizeof(name), "seed_%02d", seed);
  return name;
}

// t_ns -> pose NEES of one run's nees.csv (#t_ns,nees_position,nees_orientation,nees_pose).
std::map<Timestamp, double> ReadPoseNees(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read");
  std::map<Timestamp, double> nees;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    long long t_ns = 0;
    double position = 0, orientation = 0, pose = 0;
    if (std::sscanf(line.c_str(), "%lld,%lf,%lf,%lf", &t_ns, &position, &orientation, &pose) != 4) {
      throw std::runtime_error(path + ": bad row '" + line + "'");
    }
    nees[static_cast<Timestamp>(t_ns)] = pose;
  }
  return nees;
}

std::string FixedOrDash(double value, int digits) {
  if (!std::isfinite(value)) return "-";
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", digits, value);
  return text;
}

// A run's frame matching time t_ns: the nearest within kSameFrameNs, or none. Each run's states are at
// the IMU time of its own time offset estimate: the same frame differs between runs by their estimates.
constexpr Timestamp kSameFrameNs = 5'000'000;

const double* FrameNear(const std::map<Timestamp, double>& nees, Timestamp t_ns) {
  auto after = nees.lower_bound(t_ns);
  const double* best = nullptr;
  Timestamp best_gap = kSameFrameNs + 1;
  if (after != nees.end() && after->first - t_ns < best_gap) {
    best_gap = after->first - t_ns;
    best = &after->second;
  }
  if (after != nees.begin() && t_ns - std::prev(after)->first < best_gap) best = &std::prev(after)->second;
  return best;
}

// The per-frame run-mean pose NEES of frames every run has (the first run's times), and the share within
// bounds.
void NeesOverTime(const std::vector<const SweepResult*>& runs, MonteCarloSummary* summary) {
  std::vector<std::map<Timestamp, double>> per_run;
  for (const SweepResult* r : runs) per_run.push_back(ReadPoseNees(r->run.run_dir + "/nees.csv"));
  if (per_run.empty()) return;
  int in_bounds = 0;
  Timestamp first = -1;
  for (const auto& [t_ns, nees] : per_run.front()) {
    double sum = nees;
    bool everyone = true;
    for (size_t k = 1; k < per_run.size() && everyone; ++k) {
      const double* other = FrameNear(per_run[k], t_ns);
      everyone = other != nullptr;
      if (other) sum += *other;
    }
    if (!everyone) continue;
    if (first < 0) first = t_ns;
    const double mean = sum / summary->runs;
    summary->nees_over_time.emplace_back(NanosToSeconds(t_ns - first), mean);
    in_bounds += mean >= summary->lower_pose && mean <= summary->upper_pose;
  }
  if (!summary->nees_over_time.empty()) {
    summary->fraction_in_bounds = static_cast<double>(in_bounds) / summary->nees_over_time.size();
  }
}

// The time offset's error and NEES over the runs with an estimate, a sigma and a true offset.
void TimeOffsetConsistency(const std::vector<const SweepResult*>& runs, MonteCarloSummary* summary) {
  std::vector<const SweepResult*> with_truth;
  for (const SweepResult* r : runs) {
    if (std::isfinite(r->time_offset_ms) && std::isfinite(r->true_time_offset_ms) &&
        std::isfinite(r->time_offset_sigma_ms) && r->time_offset_sigma_ms > 0) {
      with_truth.push_back(r);
    }
  }
  summary->offset_runs = static_cast<int>(with_truth.size());
  if (with_truth.empty()) return;
  const double n = static_cast<double>(with_truth.size());
  double squares = 0;
  for (const SweepResult* r : with_truth) {
    const double error = r->time_offset_ms - r->true_time_offset_ms;
    summary->offset_mean_error_ms += error / n;
    squares += error * error / n;
    summary->offset_mean_sigma_ms += r->time_offset_sigma_ms / n;
    summary->anees_time_offset += (error / r->time_offset_sigma_ms) * (error / r->time_offset_sigma_ms) / n;
  }
  summary->offset_rms_error_ms = std::sqrt(squares);
  const ChiSquareBounds bounds = AneesBounds95(1, summary->offset_runs);
  summary->lower_time_offset = bounds.lower;
  summary->upper_time_offset = bounds.upper;
}

std::string TimeOffsetMarkdown(const std::vector<MonteCarloSummary>& summaries) {
  std::string md =
      "\nThe camera-IMU time offset's final estimate against the simulated one (mav0/rig_truth.yaml), one per run; "
      "NEES = (error / sigma)^2, 1 dof:\n\n"
      "| policy | window | runs | mean error [ms] | RMS error [ms] | mean sigma [ms] | NEES (1) | 95% bounds |\n"
      "|---|---:|---:|---:|---:|---:|---:|---|\n";
  bool any = false;
  for (const MonteCarloSummary& s : summaries) {
    if (s.offset_runs == 0) continue;
    any = true;
    md += "| " + s.policy + " | " + std::to_string(s.window_size) + " | " + std::to_string(s.offset_runs) + " | " +
          FixedOrDash(s.offset_mean_error_ms, 3) + " | " + FixedOrDash(s.offset_rms_error_ms, 3) + " | " +
          FixedOrDash(s.offset_mean_sigma_ms, 3) + " | " + FixedOrDash(s.anees_time_offset, 2) + " | [" +
          FixedOrDash(s.lower_time_offset, 2) + ", " + FixedOrDash(s.upper_time_offset, 2) + "] |\n";
  }
  return any ? md : "";
}

}  // namespace

std::vector<std::string> SimulateSeedDatasets(const SweepRequest& request, std::ostream& progress) {
  std::vector<std::string> datasets;
  for (int seed = 1; seed <= request.seeds; ++seed) {
    const std::string dir = fs::absolute(request.output_dir).lexically_normal().string() + "/datasets/" +
                            SeedName(seed);
    datasets.push_back(dir);
    if (fs::exists(dir + "/done")) continue;
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::vector<std::string> argv = {request.vio_binary, "simulate", "--output_dir=" + dir,
                                     "--noise_seed=" + std::to_string(seed)};
    argv.insert(argv.end(), request.simulate_flags.begin(), request.simulate_flags.end());
    const std::string log = dir + "/simulate.log";
    const int exit_code = WaitProcess(SpawnProcess(argv, log));
    if (exit_code != 0) {
      throw std::runtime_error("vio simulate for " + SeedName(seed) + " failed (exit " + std::to_string(exit_code) +
                               "): " + LastLine(log) + " (log: " + log + ")");
    }
    WriteDoneMarker(dir, exit_code);
    progress << "simulated " << SeedName(seed) << " (noise seed " << seed << ") in " << dir << std::endl;
  }
  return datasets;
}

std::vector<MonteCarloSummary> SummarizeMonteCarlo(const std::vector<SweepResult>& results) {
  std::vector<MonteCarloSummary> summaries;
  std::map<std::pair<std::string, int>, std::vector<const SweepResult*>> groups;
  for (const SweepResult& r : results) {
    const auto key = std::make_pair(r.run.PolicyLabel(), r.run.window_size);
    if (!groups.count(key)) {
      MonteCarloSummary summary;
      summary.policy = r.run.PolicyLabel();
      summary.window_size = r.run.window_size;
      summaries.push_back(summary);
    }
    std::vector<const SweepResult*>& group = groups[key];
    if (r.Ok() && std::isfinite(r.nees_pose)) group.push_back(&r);
  }
  for (MonteCarloSummary& s : summaries) {
    const std::vector<const SweepResult*>& runs = groups[{s.policy, s.window_size}];
    s.runs = static_cast<int>(runs.size());
    if (s.runs == 0) continue;
    for (const SweepResult* r : runs) {
      s.mean_ate_m += r->ate_rmse_m / s.runs;
      s.anees_pose += r->nees_pose / s.runs;
      s.anees_position += r->nees_position / s.runs;
      s.anees_orientation += r->nees_orientation / s.runs;
    }
    const ChiSquareBounds bounds = AneesBounds95(6, s.runs);
    s.lower_pose = bounds.lower;
    s.upper_pose = bounds.upper;
    NeesOverTime(runs, &s);
    TimeOffsetConsistency(runs, &s);
  }
  return summaries;
}

std::string MonteCarloMarkdown(const std::vector<MonteCarloSummary>& summaries) {
  std::string md =
      "| policy | window | runs | mean ATE [m] | ANEES pose (6) | 95% bounds | frames within | ANEES position (3) | "
      "ANEES orientation (3) |\n|---|---:|---:|---:|---:|---|---:|---:|---:|\n";
  for (const MonteCarloSummary& s : summaries) {
    md += "| " + s.policy + " | " + std::to_string(s.window_size) + " | " + std::to_string(s.runs) + " | " +
          (s.runs ? FixedOrDash(s.mean_ate_m, 4) : "-") + " | " + (s.runs ? FixedOrDash(s.anees_pose, 2) : "-") + " | " +
          (s.runs ? "[" + FixedOrDash(s.lower_pose, 2) + ", " + FixedOrDash(s.upper_pose, 2) + "]" : "-") + " | " +
          (s.runs ? FixedOrDash(100 * s.fraction_in_bounds, 0) + " %" : "-") + " | " +
          (s.runs ? FixedOrDash(s.anees_position, 2) : "-") + " | " + (s.runs ? FixedOrDash(s.anees_orientation, 2) : "-") +
          " |\n";
  }
  return md + TimeOffsetMarkdown(summaries);
}

}  // namespace vio::tools
