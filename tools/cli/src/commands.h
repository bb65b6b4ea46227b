#pragma once
// The subcommands' entry points (one file each: cmd_<name>.cc). Private to
// the tools library: cli.cc lists them in Subcommands().
#include <string>
#include <vector>

#include <gflags/gflags_declare.h>

/// The output folder of any command (defined once in cli.cc).
DECLARE_string(output_dir);

namespace vio::tools {

int RunMain(const std::vector<std::string>& args);
int SimulateMain(const std::vector<std::string>& args);
int EvalMain(const std::vector<std::string>& args);
int VerifyMain(const std::vector<std::string>& args);
int SweepMain(const std::vector<std::string>& args);
int ConvertMain(const std::vector<std::string>& args);
int ImageStatsMain(const std::vector<std::string>& args);
int MatchCheckMain(const std::vector<std::string>& args);

}  // namespace vio::tools
