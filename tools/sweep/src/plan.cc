// `vio sweep`: the combinations, their `vio run` command lines and jobs.txt.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <tuple>
#include <stdexcept>

#include "vio/sweep/sweep.h"

namespace vio::tools {
namespace {

namespace fs = std::filesystem;

// The flags the sweep sets itself for every run.
const std::set<std::string>& SweepOwnedFlags() {
  static const std::set<std::string> owned = {"dataset", "output_dir", "policy", "window_size", "config"};
  return owned;
}

std::string AbsolutePath(const std::string& path) { return fs::absolute(path).lexically_normal().string(); }

// "a/b/V2_01/" -> "V2_01".
std::string FolderName(const std::string& absolute_dir) {
  fs::path p(absolute_dir);
  if (p.filename().empty()) p = p.parent_path();
  return p.filename().string();
}

// Names go into folder names and shell lines: letters, digits, '_', '-', '.'.
void CheckName(const std::string& what, const std::string& name) {
  const bool safe = !name.empty() && name != "." && name != ".." &&
                    std::all_of(name.begin(), name.end(), [](char c) {
                      return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
                    });
  if (!safe) throw std::invalid_argument(what + " '" + name + "': use letters, digits, '_', '-' or '.'");
}

// The dataset folders, absolute, checked, with unique names.
std::vector<std::pair<std::string, std::string>> NamedDatasets(const std::vector<std::string>& datasets) {
  std::vector<std::pair<std::string, std::string>> named;  // (name, absolute dir)
  std::set<std::string> names;
  for (const std::string& dataset : datasets) {
    if (!fs::is_directory(dataset)) throw std::invalid_argument("dataset folder not found: " + dataset);
    const std::string dir = AbsolutePath(dataset);
    const std::string name = FolderName(dir);
    CheckName("dataset folder name", name);
    if (!names.insert(name).second) {
      throw std::invalid_argument("two datasets are named '" + name + "' (runs are filed by folder name)");
    }
    named.emplace_back(name, dir);
  }
  return named;
}

void CheckRequest(const SweepRequest& request) {
  if (request.datasets.empty()) throw std::invalid_argument("no datasets to sweep");
  if (request.policies.empty()) throw std::invalid_argument("no policies to sweep");
  if (request.window_sizes.empty()) throw std::invalid_argument("no window sizes to sweep");
  if (request.output_dir.empty()) throw std::invalid_argument("the sweep needs an output folder");
  for (const std::string& policy : request.policies) CheckName("policy", policy);
  for (int window : request.window_sizes) {
    if (window < 1) throw std::invalid_argument("window size " + std::to_string(window) + " < 1");
  }
}

// "--name=value" -> "name"; std::invalid_argument for anything else.
std::string FlagName(const std::string& flag) {
  const size_t dashes = flag.rfind("--", 0) == 0 ? 2 : flag.rfind('-', 0) == 0 ? 1 : 0;
  const size_t eq = flag.find('=');
  if (dashes == 0 || eq == std::string::npos || eq == dashes) {
    throw std::invalid_argument("run flag '" + flag + "' is not of the form --name=value");
  }
  return flag.substr(dashes, eq - dashes);
}

}  // namespace

std::string SweepRun::PolicyLabel() const {
  return local_map_keyframes > 0 ? policy + "+map" + std::to_string(local_map_keyframes) : policy;
}

std::string SweepRun::Label() const { return dataset_name + " " + PolicyLabel() + "_" + std::to_string(window_size); }

std::vector<SweepRun> PlanSweep(const SweepRequest& request) {
  CheckRequest(request);
  const std::string runs_dir = AbsolutePath(request.output_dir) + "/runs";
  std::vector<SweepCombination> combinations = request.combinations;
  if (combinations.empty()) {
    for (const std::string& policy : request.policies) {
      for (int window : request.window_sizes) combinations.push_back({policy, window, 0});
    }
  }
  std::set<std::tuple<std::string, int, int>> listed;
  for (const auto& [policy, window, keyframes] : combinations) {
    CheckName("policy", policy);
    if (window < 1) throw std::invalid_argument("window size " + std::to_string(window) + " < 1");
    if (keyframes < 0) throw std::invalid_argument("local map keyframes " + std::to_string(keyframes) + " < 0");
    if (!listed.emplace(policy, window, keyframes).second) {
      throw std::invalid_argument("run " + policy + ":" + std::to_string(window) +
                                  (keyframes > 0 ? ":" + std::to_string(keyframes) : "") +
                                  " is listed twice (each run has one folder)");
    }
  }
  std::vector<SweepRun> plan;
  for (const auto& [name, dir] : NamedDatasets(request.datasets)) {
    for (const auto& [policy, window, keyframes] : combinations) {
      SweepRun run;
      run.dataset_name = name;
      run.dataset_dir = dir;
      run.policy = policy;
      run.window_size = window;
      run.local_map_keyframes = keyframes;
      run.run_dir = runs_dir + "/" + name + "/" + run.PolicyLabel() + "_" + std::to_string(window);
      plan.push_back(run);
    }
  }
  return plan;
}

std::vector<std::string> RunArguments(const SweepRequest& request, const SweepRun& run) {
  std::vector<std::string> argv = {request.vio_binary,
                                   "run",
                                   "--dataset=" + run.dataset_dir,
                                   "--output_dir=" + run.run_dir,
                                   "--policy=" + run.policy,
                                   "--window_size=" + std::to_string(run.window_size)};
  if (run.local_map_keyframes > 0) argv.push_back("--local_map_keyframes=" + std::to_string(run.local_map_keyframes));
  if (!request.config_path.empty()) argv.push_back("--config=" + AbsolutePath(request.config_path));
  for (const std::string& flag : request.run_flags) {
    if (SweepOwnedFlags().count(FlagName(flag)) > 0) {
      throw std::invalid_argument("run flag '" + flag + "' is set by the sweep itself for every run");
    }
    if (run.local_map_keyframes > 0 && FlagName(flag) == "local_map_keyframes") {
      throw std::invalid_argument("run flag '" + flag + "' and the run " + run.Label() +
                                  " both set the local map's keyframes");
    }
    argv.push_back(flag);
  }
  return argv;
}

std::string ShellQuote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::vector<std::string> SplitFlags(const std::string& text) {
  std::vector<std::string> tokens;
  std::string token;
  bool in_token = false;
  char quote = 0;
  for (char c : text) {
    if (quote != 0) {
      if (c == quote) quote = 0;
      else token += c;
    } else if (c == '\'' || c == '"') {
      quote = c;
      in_token = true;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      if (in_token) tokens.push_back(token);
      token.clear();
      in_token = false;
    } else {
      token += c;
      in_token = true;
    }
  }
  if (quote != 0) throw std::invalid_argument("unterminated quote in flags: " + text);
  if (in_token) tokens.push_back(token);
  return tokens;
}

std::string JobCommand(const SweepRequest& request, const SweepRun& run) {
  std::string command;
  for (const std::string& arg : RunArguments(request, run)) command += (command.empty() ? "" : " ") + ShellQuote(arg);
  return "d=" + ShellQuote(run.run_dir) + "; [ -f \"$d/done\" ] || { rm -rf \"$d\" && mkdir -p \"$d\" && " +
         command + " >\"$d/run.log\" 2>&1; rc=$?; if [ -f \"$d/summary.json\" ] && [ $rc -ne 130 ] && [ $rc -ne 143 ]; then echo \"exit_code=$rc\" " +
         ">\"$d/done.tmp\" && mv \"$d/done.tmp\" \"$d/done\"; fi; exit $rc; }";
}

std::string WriteJobsFile(const SweepRequest& request) {
  const std::vector<SweepRun> plan = PlanSweep(request);
  fs::create_directories(request.output_dir);
  const std::string path = AbsolutePath(request.output_dir) + "/jobs.txt";
  std::ofstream out(path);
  for (const SweepRun& run : plan) out << JobCommand(request, run) << "\n";
  if (!out) throw std::runtime_error(path + ": cannot write");
  return path;
}

}  // namespace vio::tools
