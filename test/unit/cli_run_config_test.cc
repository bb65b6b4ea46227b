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

// Long-lived landmarks are an option of the windowed policies: asking for them
// with another policy, or for a negative budget, names the option.
TEST(RunConfig, PersistentLandmarksAreCheckedAgainstThePolicy) {
  const std::string dir = test::MakeTempDir("run_config");
  const std::string path = dir + "/persistent.yaml";
  std::ofstream(path) << "policy:\n  policy: ekf\npersistent:\n  persistent_landmarks: 20\n";
  try {
    LoadRunConfig(path);
    FAIL() << "persistent_landmarks accepted with ekf";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("--persistent_landmarks=20"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("ekf"), std::string::npos) << e.what();
  }
  std::ofstream(path) << "policy:\n  policy: msckf\npersistent:\n  persistent_landmarks: 20\n";
  EXPECT_EQ(LoadRunConfig(path).estimator.persistent.persistent_landmarks, 20);
  std::ofstream(path) << "persistent:\n  persistent_landmarks: -1\n";
  try {
    LoadRunConfig(path);
    FAIL() << "a negative budget accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("persistent_landmarks"), std::string::npos) << e.what();
  }
}

// The local map is an option of swf and msckf alone, with a window of at least 2,
// and not together with long-lived landmarks: each refusal names the option.
TEST(RunConfig, LocalMapIsCheckedAgainstThePolicy) {
  const std::string dir = test::MakeTempDir("run_config");
  const std::string path = dir + "/local_map.yaml";
  const auto refused = [&](const std::string& yaml, const std::string& expected) {
    std::ofstream(path) << yaml;
    try {
      LoadRunConfig(path);
      ADD_FAILURE() << "accepted: " << yaml;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("--local_map_keyframes=8"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  };
  refused("policy:\n  policy: ekf\nlocal_map:\n  local_map_keyframes: 8\n", "ekf");
  refused("policy:\n  window_size: 1\nlocal_map:\n  local_map_keyframes: 8\n", "window_size");
  refused("persistent:\n  persistent_landmarks: 5\nlocal_map:\n  local_map_keyframes: 8\n", "persistent_landmarks");
  std::ofstream(path) << "policy:\n  policy: msckf\nlocal_map:\n  local_map_keyframes: 8\n";
  EXPECT_EQ(LoadRunConfig(path).estimator.local_map.local_map_keyframes, 8);
}

}  // namespace
}  // namespace vio::tools
