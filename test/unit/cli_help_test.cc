// `vio <command> --help` as a user reads it (the real binary, VIO_BINARY):
// every flag a command reads is listed, flags it ignores are not, defaults
// print as written, and a stray argument is named as such.
#include <sys/wait.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_data.h"

namespace vio::tools {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

struct Output {
  int exit_code = -1;
  std::string text;  // stdout and stderr
};

Output Vio(const std::string& args) {
  const std::string log = test::MakeTempDir("cli_help") + "/out.log";
  const int status = std::system((std::string(VIO_BINARY) + " " + args + " > " + log + " 2>&1").c_str());
  std::ifstream in(log);
  std::stringstream text;
  text << in.rdbuf();
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, text.str()};
}

// `vio <command> --help`, run once per command.
const Output& Help(const std::string& command) {
  static std::map<std::string, Output> helps;
  auto it = helps.find(command);
  if (it == helps.end()) it = helps.emplace(command, Vio(command + " --help")).first;
  return it->second;
}

TEST(CliHelp, EveryCommandListsItsOwnFlagsAndTheLoggingFlags) {
  for (const char* command : {"run", "simulate", "eval", "verify", "sweep"}) {
    const Output& help = Help(command);
    EXPECT_EQ(help.exit_code, 0) << command;
    EXPECT_THAT(help.text, HasSubstr("usage: vio " + std::string(command))) << command;
    EXPECT_THAT(help.text, HasSubstr("\n  --v=0 (int32)")) << command;
    EXPECT_THAT(help.text, HasSubstr("\n  --minloglevel=0 (int32)")) << command;
  }
}

TEST(CliHelp, SharedFlagsAppearWhereTheyAreReadAndNowhereElse) {
  EXPECT_THAT(Help("verify").text, HasSubstr("\n  --seed=1 (uint64)"));
  EXPECT_THAT(Help("simulate").text, HasSubstr("\n  --seed=1 (uint64)"));
  EXPECT_THAT(Help("run").text, Not(HasSubstr("--seed=")));
  for (const char* command : {"eval", "verify"}) {
    EXPECT_THAT(Help(command).text, Not(HasSubstr("--output_dir="))) << command;
  }
  for (const char* command : {"run", "simulate", "sweep"}) {
    EXPECT_THAT(Help(command).text, HasSubstr("\n  --output_dir= (string)")) << command;
  }
  const std::string sweep = Help("sweep").text;
  EXPECT_THAT(sweep, HasSubstr("\n  --config= (string)"));
  EXPECT_THAT(sweep, HasSubstr("run configuration"));
  EXPECT_THAT(Help("eval").text, Not(HasSubstr("run configuration")));
}

TEST(CliHelp, DefaultsPrintInTheirShortestExactForm) {
  const std::string help = Help("run").text;
  EXPECT_THAT(help, HasSubstr("--klt_min_ncc=0.8 (double)"));
  EXPECT_THAT(help, Not(HasSubstr("0000000")));
  EXPECT_THAT(help, Not(HasSubstr("9999999")));
}

TEST(CliHelp, AStrayArgumentIsNamedNotMistakenForAMissingFlag) {
  const Output run = Vio("run --dataset=/nonexistent --output_dir=/nonexistent extra");
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_THAT(run.text, HasSubstr("unexpected argument 'extra'"));
  EXPECT_THAT(run.text, Not(HasSubstr("required")));
  const Output missing = Vio("run --dataset=/nonexistent");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_THAT(missing.text, HasSubstr("--output_dir is required"));
}

TEST(CliHelp, SimulateNamesABadJumpModeOrRoomMarginAndWritesNothing) {
  const std::string dir = test::MakeTempDir("cli_help") + "/sim";
  const Output jumps = Vio("simulate --output_dir=" + dir + " --groundtruth_jumps=smooth");
  EXPECT_EQ(jumps.exit_code, 2);
  EXPECT_THAT(jumps.text, HasSubstr("--groundtruth_jumps=smooth: expected 'remove' or 'keep'"));
  const Output margin = Vio("simulate --output_dir=" + dir + " --room_margin=-1");
  EXPECT_EQ(margin.exit_code, 2);
  EXPECT_THAT(margin.text, HasSubstr("room margin around the trajectory must be >= 0"));
  std::ifstream imu(dir + "/mav0/imu0/data.csv");
  EXPECT_FALSE(imu.good());
}

}  // namespace
}  // namespace vio::tools
