#include "vio/cli/cli.h"

#include <algorithm>
#include <charconv>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

#include <gflags/gflags.h>
#include <glog/logging.h>

#include "commands.h"
#include "vio/cli/run_config.h"

DEFINE_string(output_dir, "", "output folder of the command (created when missing)");

namespace vio::tools {
namespace {

void PrintTopLevelHelp(std::ostream& os) {
  os << "vio: stereo-inertial sliding-window estimation (one cost, many policies)\n\n"
        "usage: vio <command> [--flag=value ...]\n\ncommands:\n";
  for (const Subcommand& cmd : Subcommands()) {
    os << "  " << cmd.name << std::string(12 - std::min<size_t>(11, cmd.name.size()), ' ')
       << cmd.summary << "\n";
  }
  os << "\n`vio <command> --help` lists the command's flags.\n";
}

bool EndsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// A default as written on the command line: doubles in their shortest exact
// form (gflags writes 0.8 as 0.80000000000000004).
std::string DefaultText(const gflags::CommandLineFlagInfo& f) {
  if (f.type != "double") return f.default_value;
  const double value = std::strtod(f.default_value.c_str(), nullptr);
  char text[32];
  const auto [end, ec] = std::to_chars(text, text + sizeof(text), value);
  return ec == std::errc() ? std::string(text, end) : f.default_value;
}

void PrintFlag(const gflags::CommandLineFlagInfo& f, std::ostream& os) {
  os << "  --" << f.name << "=" << DefaultText(f) << " (" << f.type << ")\n      " << f.description << "\n";
}

// The flags a command takes: those defined in its own source file
// (cmd_<name>.cc), the shared ones it names, every estimator/front-end option
// (registered from the Options structs, file name "options/<section>") when
// it takes the run configuration, and glog's verbosity flags.
void PrintCommandHelp(const Subcommand& cmd, std::ostream& os) {
  os << "vio " << cmd.name << ": " << cmd.summary << "\n\nusage: " << cmd.usage << "\n\nflags:\n";
  std::vector<gflags::CommandLineFlagInfo> flags;
  gflags::GetAllFlags(&flags);
  const std::string own = "cmd_" + cmd.name + ".cc";
  auto shared = [&](const std::string& name) {
    return std::find(cmd.shared_flags.begin(), cmd.shared_flags.end(), name) != cmd.shared_flags.end();
  };
  for (const auto& f : flags) {
    if (EndsWith(f.filename, own) || shared(f.name)) PrintFlag(f, os);
  }
  if (cmd.takes_run_config) {
    os << "\nrun configuration (each also a key of the --config YAML; the flag wins):\n";
    for (const auto& f : flags) {
      if (f.filename.rfind("options/", 0) == 0) PrintFlag(f, os);
    }
  }
  os << "\nlogging (glog, to stderr; every command):\n";
  const std::pair<const char*, const char*> logging[] = {
      {"v", "verbose logging: also show VLOG(m) messages for m <= this"},
      {"minloglevel", "show only messages at this level or above: 0 INFO, 1 WARNING, 2 ERROR"}};
  for (const auto& [name, description] : logging) {
    gflags::CommandLineFlagInfo f;
    if (!gflags::GetCommandLineFlagInfo(name, &f)) continue;
    f.description = description;
    PrintFlag(f, os);
  }
}

const Subcommand* FindSubcommand(const std::string& name) {
  for (const Subcommand& cmd : Subcommands()) {
    if (cmd.name == name) return &cmd;
  }
  return nullptr;
}

bool WantsHelp(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--help") == 0 || std::strcmp(argv[i], "-h") == 0) return true;
  }
  return false;
}

}  // namespace

const std::vector<Subcommand>& Subcommands() {
  static const std::vector<Subcommand> commands = {
      {"run", "run the estimator over one EuRoC-format dataset",
       "vio run --dataset=DIR --output_dir=DIR [--config=FILE] [--policy=swf --window_size=10 ...]", &RunMain,
       {"output_dir"}, /*takes_run_config=*/true},
      {"simulate", "generate a synthetic or hybrid EuRoC-format dataset",
       "vio simulate --output_dir=DIR [--from=EUROC_DIR] [--camera=features|images] [--seed=N]", &SimulateMain,
       {"output_dir"}},
      {"eval", "trajectory error (ATE, RPE) of an estimate against ground truth",
       "vio eval --estimate=FILE --groundtruth=FILE_OR_DIR [--alignment=posyaw|se3|sim3|none] [--json=FILE]",
       &EvalMain},
      {"verify", "check the paper's filter = optimization theorems through the estimator's window on random problems",
       "vio verify [--seed=N] [--num_landmarks=N] [--num_poses=N] [--trials=N] [--json=FILE]", &VerifyMain, {"seed", "json"}},
      {"sweep", "run every dataset x policy x window size, N at a time; table, CSV, plots and report",
       "vio sweep --datasets=DIR,... --policies=swf,... --window_sizes=5,10,... --output_dir=DIR [--jobs=N] "
       "[--config=FILE] [--extra_flags=\"--init=groundtruth ...\"] [--emit_jobs | --collect_only]",
       &SweepMain, {"output_dir", "config"}, /*takes_run_config=*/true},
      {"convert", "an ASL folder with images to a ROS 1 bag or ROS 2 recording, or back to an ASL folder",
       "vio convert --input=DIR_OR_BAG --output=BAG_OR_DIR [--storage=mcap|sqlite3] [--compression=zstd|lz4|none] "
       "[--calibration=DIR] [--cam0_topic=/cam0/image_raw ...]",
       &ConvertMain, {}, /*takes_run_config=*/true},
      {"imagestats", "grey level, contrast, gradient, corner and KLT statistics of stereo image sequences, as a table",
       "vio imagestats --datasets=DIR,... [--max_frames=200] [--config=FILE]", &ImageStatsMain, {"config", "datasets"},
       /*takes_run_config=*/true},
      {"matchcheck", "a run's front-end matches against the scene of a dataset `vio simulate` made",
       "vio matchcheck --dataset=DIR --run=RUN_DIR [--max_error_px=3] [--json=FILE]", &MatchCheckMain,
       {"dataset", "json"}},
  };
  return commands;
}

int RunCli(int argc, char** argv) {
  google::InitGoogleLogging(argv[0]);
  FLAGS_logtostderr = true;
  RegisterRunConfigFlags();
  if (argc < 2 || std::strcmp(argv[1], "--help") == 0 || std::strcmp(argv[1], "-h") == 0 ||
      std::strcmp(argv[1], "help") == 0) {
    PrintTopLevelHelp(std::cout);
    return argc < 2 ? 2 : 0;
  }
  const Subcommand* cmd = FindSubcommand(argv[1]);
  if (cmd == nullptr) {
    std::cerr << "vio: unknown command '" << argv[1] << "'\n\n";
    PrintTopLevelHelp(std::cerr);
    return 2;
  }
  // argv[1] is the command: gflags parses the rest.
  int sub_argc = argc - 1;
  char** sub_argv = argv + 1;
  if (WantsHelp(sub_argc, sub_argv)) {
    PrintCommandHelp(*cmd, std::cout);
    return 0;
  }
  gflags::SetUsageMessage(cmd->usage);
  gflags::ParseCommandLineFlags(&sub_argc, &sub_argv, /*remove_flags=*/true);
  std::vector<std::string> args(sub_argv + 1, sub_argv + sub_argc);
  try {
    return cmd->main(args);
  } catch (const std::exception& e) {
    std::cerr << "vio " << cmd->name << ": error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace vio::tools
