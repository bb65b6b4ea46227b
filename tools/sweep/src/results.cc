// `vio sweep`: reading run folders, the progress lines and the result tables.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "internal.h"
#include "json.h"
#include "vio/evaluation/nees.h"
#include "vio/sweep/sweep.h"

namespace vio::tools {
namespace {

namespace fs = std::filesystem;

std::string ReadText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot read");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// "exit_code=<n>" -> n.
int ReadMarker(const std::string& path) {
  const std::string text = ReadText(path);
  int exit_code = -1;
  if (std::sscanf(text.c_str(), "exit_code=%d", &exit_code) != 1) {
    throw std::runtime_error(path + ": not a sweep marker (exit_code=<n>)");
  }
  return exit_code;
}

double NumberOf(const JsonValue& object, const std::string& key) {
  const JsonValue* value = object.Find(key);
  return value == nullptr ? SweepResult::kNaN : value->AsNumber();
}

void ReadEvaluation(const JsonValue& evaluation, SweepResult* result) {
  if (const JsonValue* ate = evaluation.Find("ate")) result->ate_rmse_m = NumberOf(*ate, "rmse_m");
  const JsonValue* rpe = evaluation.Find("rpe");
  if (rpe == nullptr) return;
  for (const JsonValue& item : rpe->items) {
    result->rpe.push_back({NumberOf(item, "length_m"), NumberOf(item, "trans_pct"), NumberOf(item, "rot_deg_per_m")});
  }
}

void ReadSummary(const std::string& path, SweepResult* result) {
  const JsonValue summary = ParseJson(ReadText(path), path);
  const JsonValue* status = summary.Find("status");
  if (status == nullptr || status->type != JsonValue::Type::kString) {
    throw std::runtime_error(path + ": no \"status\"");
  }
  result->status = status->string;
  result->ms_per_frame = NumberOf(summary, "ms_per_frame");
  result->real_time_factor = NumberOf(summary, "real_time_factor");
  result->peak_memory_mb = NumberOf(summary, "peak_memory_mb");
  if (const JsonValue* reason = summary.Find("not_initialized_reason")) result->message = reason->string;
  if (const JsonValue* evaluation = summary.Find("evaluation")) ReadEvaluation(*evaluation, result);
  if (const JsonValue* calibration = summary.Find("calibration")) {
    result->time_offset_ms = NumberOf(*calibration, "time_offset_ms");
    result->time_offset_sigma_ms = NumberOf(*calibration, "time_offset_sigma_ms");
  }
  if (const JsonValue* nees = summary.Find("nees")) {
    result->nees_pose = NumberOf(*nees, "pose");
    result->nees_position = NumberOf(*nees, "position");
    result->nees_orientation = NumberOf(*nees, "orientation");
  }
}

// time_offset_ms of a dataset's rig_truth.yaml (vio simulate); NaN without the file.
double ReadTrueTimeOffset(const std::string& path) {
  if (!fs::exists(path)) return SweepResult::kNaN;
  try {
    const YAML::Node truth = YAML::LoadFile(path);
    if (!truth["time_offset_ms"]) throw std::runtime_error("no time_offset_ms");
    return truth["time_offset_ms"].as<double>();
  } catch (const std::exception& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
}

std::string Fixed(double value, int digits) {
  if (!std::isfinite(value)) return "";
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", digits, value);
  return text;
}

// 10 significant digits (CSV); empty for NaN.
std::string Exact(double value) {
  if (!std::isfinite(value)) return "";
  std::ostringstream os;
  os.precision(10);
  os << value;
  return os.str();
}

std::string CsvField(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

// Every RPE length any run reports, increasing.
std::vector<double> RpeLengths(const std::vector<SweepResult>& results) {
  std::set<double> lengths;
  for (const SweepResult& r : results) {
    for (const SweepRpe& rpe : r.rpe) lengths.insert(rpe.length_m);
  }
  return {lengths.begin(), lengths.end()};
}

const SweepRpe* RpeAt(const SweepResult& result, double length_m) {
  for (const SweepRpe& rpe : result.rpe) {
    if (rpe.length_m == length_m) return &rpe;
  }
  return nullptr;
}

std::string StatusText(const SweepResult& r) {
  if (r.Ok()) return "ok";
  std::string text = r.status == "failed" ? "FAILED" : r.status;
  if (r.exit_code >= 0) text += " (exit " + std::to_string(r.exit_code) + ")";
  return text;
}

// Markdown bullets: why each run that is not ok is not.
std::string FailureNotes(const std::vector<SweepResult>& results) {
  std::string notes;
  for (const SweepResult& r : results) {
    if (r.Ok()) continue;
    notes += "- " + r.run.Label() + ": " + StatusText(r) + (r.message.empty() ? "" : ": `" + r.message + "`") + "\n";
  }
  return notes.empty() ? notes : "\nNot ok:\n\n" + notes;
}

}  // namespace

SweepResult ReadRunResult(const SweepRun& run) {
  SweepResult result;
  result.run = run;
  if (!IsRunFinished(run)) {
    const std::string log = run.run_dir + "/run.log";
    result.message = fs::exists(log) ? "unfinished: " + LastLine(log) : "not run yet";
    return result;
  }
  try {
    result.exit_code = ReadMarker(run.run_dir + "/done");
    ReadSummary(run.run_dir + "/summary.json", &result);
    result.true_time_offset_ms = ReadTrueTimeOffset(run.dataset_dir + "/mav0/rig_truth.yaml");
  } catch (const std::exception& e) {
    result.status = "failed";
    result.message = e.what();
  }
  return result;
}

std::string ProgressLine(const SweepResult& r, int index, int total) {
  std::string line = "[" + std::to_string(index) + "/" + std::to_string(total) + "] " + r.run.Label() + " " +
                     StatusText(r);
  if (std::isfinite(r.ate_rmse_m)) line += " ATE " + Fixed(r.ate_rmse_m, 3) + " m";
  if (std::isfinite(r.ms_per_frame)) line += " " + Fixed(r.ms_per_frame, 1) + " ms/frame";
  if (!r.Ok() && !r.message.empty()) line += ": " + r.message;
  if (r.reused) line += " (finished earlier)";
  return line;
}

std::string ResultsCsv(const std::vector<SweepResult>& results) {
  const std::vector<double> lengths = RpeLengths(results);
  std::string csv = "dataset,policy,window,status,exit_code,ate_rmse_m";
  for (double l : lengths) csv += ",rpe_" + Exact(l) + "m_trans_pct,rpe_" + Exact(l) + "m_rot_deg_per_m";
  csv += ",ms_per_frame,real_time_factor,peak_memory_mb,nees_pose,nees_position,nees_orientation,message,run_dir\n";
  for (const SweepResult& r : results) {
    csv += r.run.dataset_name + "," + r.run.PolicyLabel() + "," + std::to_string(r.run.window_size) + "," + r.status +
           "," + (r.exit_code >= 0 ? std::to_string(r.exit_code) : "") + "," + Exact(r.ate_rmse_m);
    for (double l : lengths) {
      const SweepRpe* rpe = RpeAt(r, l);
      csv += "," + (rpe ? Exact(rpe->trans_pct) : "") + "," + (rpe ? Exact(rpe->rot_deg_per_m) : "");
    }
    csv += "," + Exact(r.ms_per_frame) + "," + Exact(r.real_time_factor) + "," + Exact(r.peak_memory_mb) + "," +
           Exact(r.nees_pose) + "," + Exact(r.nees_position) + "," + Exact(r.nees_orientation) + "," +
           CsvField(r.message) + "," + CsvField(r.run.run_dir) + "\n";
  }
  return csv;
}

std::string ResultsMarkdown(const std::vector<SweepResult>& results) {
  const std::vector<double> lengths = RpeLengths(results);
  std::string md = "| dataset | policy | window | status | ATE RMSE [m]";
  std::string rule = "|---|---|---:|---|---:";
  for (double l : lengths) {
    md += " | RPE " + Exact(l) + " m [%]";
    rule += "|---:";
  }
  md += " | ms/frame | x real time | peak memory [MB] |\n" + rule + "|---:|---:|---:|\n";
  auto cell = [](const std::string& text) { return text.empty() ? std::string("-") : text; };
  for (const SweepResult& r : results) {
    md += "| " + r.run.dataset_name + " | " + r.run.PolicyLabel() + " | " + std::to_string(r.run.window_size) + " | " +
          StatusText(r) + " | " + cell(Fixed(r.ate_rmse_m, 3));
    for (double l : lengths) {
      const SweepRpe* rpe = RpeAt(r, l);
      md += " | " + cell(rpe ? Fixed(rpe->trans_pct, 2) : "");
    }
    md += " | " + cell(Fixed(r.ms_per_frame, 1)) + " | " + cell(Fixed(r.real_time_factor, 1)) + " | " +
          cell(Fixed(r.peak_memory_mb, 0)) + " |\n";
  }
  return md;
}

void WriteResults(const SweepRequest& request, const std::vector<SweepResult>& results) {
  fs::create_directories(request.output_dir);
  const std::string csv_path = request.output_dir + "/results.csv";
  std::ofstream csv(csv_path);
  csv << ResultsCsv(results);
  if (!csv) throw std::runtime_error(csv_path + ": cannot write");
  const std::string md_path = request.output_dir + "/results.md";
  std::ofstream md(md_path);
  md << "# vio sweep: " << results.size() << " runs\n\n"
     << "ATE: RMSE of the position error after position + yaw alignment. RPE: mean translation error over\n"
        "sub-trajectories of the given length travelled, in % of the length. ms/frame: estimator time per frame.\n\n"
     << ResultsMarkdown(results) << FailureNotes(results);
  if (request.seeds > 0) {
    const ChiSquareBounds bounds = AneesBounds95(6, request.seeds);
    md << "\n## Monte Carlo: " << request.seeds << " noise seeds per configuration\n\n"
       << "ANEES: mean NEES over runs and frames (pose error [p_gt - p, Log(R^T R_gt)] with the estimate aligned\n"
          "at its first pose in position + yaw, the gauge of the estimator's first-state prior; covariance from\n"
          "the window's information). A consistent estimator has ANEES = dof; the\n"
          "run-mean NEES at one frame of N consistent runs lies within chi2(6N)/N's 95% bounds ([" << bounds.lower
       << ", " << bounds.upper << "] for N = " << request.seeds << ", Wilson-Hilferty) 95% of the time.\n\n"
       << MonteCarloMarkdown(SummarizeMonteCarlo(results));
  }
  if (!md) throw std::runtime_error(md_path + ": cannot write");
}

std::string SweepSummary(const SweepRequest& request, const std::vector<SweepResult>& results) {
  int ok = 0;
  int reused = 0;
  std::string not_ok;
  for (const SweepResult& r : results) {
    ok += r.Ok() ? 1 : 0;
    reused += r.reused ? 1 : 0;
    if (!r.Ok()) {
      not_ok += "\n  " + r.run.Label() + ": " + StatusText(r) + (r.message.empty() ? "" : ": " + r.message);
    }
  }
  std::ostringstream os;
  os << "sweep: " << results.size() << " runs, " << ok << " ok, " << results.size() - ok << " not ok";
  if (reused > 0) os << " (" << reused << " finished by an earlier sweep)";
  if (!not_ok.empty()) os << "; not ok:" << not_ok;
  os << "\nresults: " << request.output_dir << "/results.csv, " << request.output_dir << "/results.md";
  return os.str();
}

}  // namespace vio::tools
