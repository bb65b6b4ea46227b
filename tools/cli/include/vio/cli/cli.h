#pragma once
// The `vio` command: `vio <subcommand> [--flags]`.
#include <string>
#include <vector>

namespace vio::tools {

/// One subcommand: `vio <name> ...`.
struct Subcommand {
  std::string name;     ///< e.g. "run"
  std::string summary;  ///< one line for `vio --help`
  std::string usage;    ///< e.g. "vio run --dataset=DIR [--config=FILE] ..."
  /// Runs with gflags already parsed; `args` are the positional arguments.
  /// Returns the process exit code.
  int (*main)(const std::vector<std::string>& args);
  /// Flags the command takes that another file defines (e.g. "output_dir",
  /// "config", "seed"); `--help` lists them with the command's own flags.
  std::vector<std::string> shared_flags = {};
  /// Takes the run configuration (YAML + option flags); `--help` lists them.
  bool takes_run_config = false;
};

/// All subcommands, in the order `vio --help` lists them.
const std::vector<Subcommand>& Subcommands();

/// Entry point of the `vio` executable.
int RunCli(int argc, char** argv);

}  // namespace vio::tools
