// `vio sweep`: the data behind the plots (aligned trajectories, errors over
// time) and the call of tools/plot_sweep.py.
//
// plots/data/<dataset>/groundtruth.csv   t_s,x_m,y_m,z_m (t from the first ground-truth sample)
// plots/data/<dataset>/<policy>_<w>.csv  t_s,x_m,y_m,z_m,error_m: the estimate after
//                                        position + yaw alignment, and |p_est - p_gt|
// plots/data/nees/<policy>_<w>.csv       (Monte Carlo) t_s,nees_pose,lower,upper: the
//                                        run-mean pose NEES per frame and its 95% bounds
// Monte Carlo sweeps plot the trajectories of the first seed only.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include <glog/logging.h>

#include "internal.h"
#include "vio/sweep/sweep.h"
#include "vio/evaluation/trajectory_eval.h"

namespace vio::tools {
namespace {

namespace fs = std::filesystem;

constexpr size_t kMaxGroundTruthRows = 4000;  // enough for a smooth line

std::ofstream OpenCsv(const std::string& path, const std::string& header) {
  fs::create_directories(fs::path(path).parent_path());
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot write");
  out.precision(6);
  out << std::fixed << header << "\n";
  return out;
}

void WriteGroundTruth(const std::vector<GroundTruthState>& gt, const std::string& path) {
  std::ofstream out = OpenCsv(path, "t_s,x_m,y_m,z_m");
  const size_t stride = gt.size() / kMaxGroundTruthRows + 1;
  for (size_t i = 0; i < gt.size(); i += stride) {
    const Eigen::Vector3d& p = gt[i].p_w_b;
    out << NanosToSeconds(gt[i].t_ns - gt.front().t_ns) << "," << p.x() << "," << p.y() << "," << p.z() << "\n";
  }
}

void WriteAlignedEstimate(const std::vector<GroundTruthState>& gt, const std::string& trajectory_path,
                          const std::string& path) {
  const AssociatedTrajectory associated = Associate(ReadTumTrajectory(trajectory_path), gt);
  const AssociatedTrajectory aligned = ApplyAlignment(associated, Align(associated, Alignment::kPosYaw));
  std::ofstream out = OpenCsv(path, "t_s,x_m,y_m,z_m,error_m");
  for (size_t i = 0; i < aligned.t_ns.size(); ++i) {
    const Eigen::Vector3d p = aligned.T_w_b_est[i].translation();
    const double error_m = (p - aligned.T_w_b_gt[i].translation()).norm();
    out << NanosToSeconds(aligned.t_ns[i] - gt.front().t_ns) << "," << p.x() << "," << p.y() << "," << p.z()
        << "," << error_m << "\n";
  }
}

// One dataset's files; returns the number of runs written.
int WriteDatasetPlotData(const std::vector<const SweepResult*>& runs, const std::string& data_dir) {
  const std::vector<GroundTruthState> gt = ReadGroundTruthPath(runs.front()->run.dataset_dir);
  if (gt.empty()) return 0;
  WriteGroundTruth(gt, data_dir + "/groundtruth.csv");
  int written = 0;
  for (const SweepResult* r : runs) {
    const std::string trajectory = r->run.run_dir + "/trajectory.txt";
    if (r->status == "failed" || r->status == "missing" || !fs::exists(trajectory)) continue;
    try {
      WriteAlignedEstimate(gt, trajectory, data_dir + "/" + r->run.PolicyLabel() + "_" +
                                               std::to_string(r->run.window_size) + ".csv");
      ++written;
    } catch (const std::exception& e) {
      LOG(WARNING) << r->run.Label() << ": no plot data: " << e.what();
    }
  }
  return written;
}

// plots/data/nees/: one file per configuration with NEES.
void WriteNeesPlotData(const std::vector<SweepResult>& results, const std::string& plots_dir) {
  for (const MonteCarloSummary& s : SummarizeMonteCarlo(results)) {
    if (s.nees_over_time.empty()) continue;
    std::ofstream out = OpenCsv(plots_dir + "/data/nees/" + s.policy + "_" + std::to_string(s.window_size) + ".csv",
                                "t_s,nees_pose,lower,upper");
    for (const auto& [t_s, nees] : s.nees_over_time) {
      out << t_s << "," << nees << "," << s.lower_pose << "," << s.upper_pose << "\n";
    }
  }
}

// Writes plots/data; returns the number of runs with a trajectory there.
int WritePlotData(const SweepRequest& request, const std::vector<SweepResult>& results,
                  const std::string& plots_dir) {
  std::map<std::string, std::vector<const SweepResult*>> by_dataset;
  for (const SweepResult& r : results) {
    if (request.seeds == 0 || r.run.dataset_name == results.front().run.dataset_name) {
      by_dataset[r.run.dataset_name].push_back(&r);
    }
  }
  std::error_code ec;
  fs::remove_all(plots_dir + "/data", ec);
  if (request.seeds > 0) WriteNeesPlotData(results, plots_dir);
  int written = 0;
  for (const auto& [name, runs] : by_dataset) {
    try {
      written += WriteDatasetPlotData(runs, plots_dir + "/data/" + name);
    } catch (const std::exception& e) {
      LOG(WARNING) << name << ": no ground truth to plot against: " << e.what();
    }
  }
  return written;
}

}  // namespace

std::string FindPlotScript(const std::string& vio_binary) {
  std::vector<fs::path> candidates;
  if (const char* source_dir = std::getenv("VIO_SOURCE_DIR")) {
    candidates.push_back(fs::path(source_dir) / "tools/plot_sweep.py");
  }
  candidates.push_back(fs::path(__FILE__).parent_path().parent_path() / "plot_sweep.py");
  const fs::path binary_dir = fs::path(vio_binary).parent_path();
  candidates.push_back(binary_dir / "../../tools/plot_sweep.py");
  candidates.push_back(binary_dir / "../share/vio/plot_sweep.py");
  for (const fs::path& candidate : candidates) {
    if (fs::is_regular_file(candidate)) return fs::absolute(candidate).lexically_normal().string();
  }
  return "";
}

std::string MakePlots(const SweepRequest& request, const std::vector<SweepResult>& results,
                      const std::string& python, const std::string& plot_script) {
  const std::string plots_dir = fs::absolute(request.output_dir).lexically_normal().string() + "/plots";
  const int runs_with_data = results.empty() ? 0 : WritePlotData(request, results, plots_dir);
  if (runs_with_data == 0) return "plots skipped: no run has a trajectory to plot";
  if (!fs::exists(python)) {
    return "plots skipped: " + python + " not found (plots need Python 3 with numpy and matplotlib; " +
           "results.csv and results.md are complete)";
  }
  if (plot_script.empty() || !fs::is_regular_file(plot_script)) {
    return "plots skipped: plot_sweep.py not found (give --plot_script=PATH/tools/plot_sweep.py)";
  }
  const std::string log = plots_dir + "/plot.log";
  const std::string sweep_dir = fs::path(plots_dir).parent_path().string();
  const int exit_code = WaitProcess(SpawnProcess({python, plot_script, "--sweep_dir", sweep_dir}, log));
  if (exit_code != 0) {
    return "plots failed (exit " + std::to_string(exit_code) + "): " + LastLine(log) + " (log: " + log + ")";
  }
  return "plots: " + LastLine(log);
}

}  // namespace vio::tools
