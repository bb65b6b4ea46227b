#include "vio/cli/run_config.h"

#include <cstdlib>
#include <fstream>

#include <gtest/gtest.h>

#include "test_data.h"

namespace vio::tools {
namespace {

std::string SourceDir() {
  const char* dir = std::getenv("VIO_SOURCE_DIR");
  return dir != nullptr ? dir : ".";
}

TEST(RunConfig, ShippedConfigLoadsAndEqualsTheBuiltInDefaults) {
  const std::string path = SourceDir() + "/config/euroc_stereo.yaml";
  ASSERT_TRUE(test::PathExists(path)) << path;
  const RunConfig loaded = LoadRunConfig(path);
  EXPECT_EQ(RunConfigToYaml(loaded), RunConfigToYaml(RunConfig{}));
}

TEST(RunConfig, UnknownKeyInARunFileIsAnError) {
  const std::string dir = test::MakeTempDir("run_config");
  const std::string path = dir + "/bad.yaml";
  std::ofstream(path) << "policy:\n  window_sise: 30\n";
  try {
    LoadRunConfig(path);
    FAIL() << "unknown key accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.yaml:2: unknown key 'window_sise'"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace vio::tools
