#include "vio/cli/options_registry.h"

#include <gflags/gflags.h>
#include <gtest/gtest.h>

#include "vio/estimator/estimator_options.h"

namespace vio::tools {
namespace {

struct DemoOptions {
  int count = 3;
  double rate_hz = 20.0;
  bool enabled = true;
  std::string mode = "fast";
  std::int64_t start_ns = 7;
  template <class V>
  void Visit(V& v) {
    v("demo_count", count, "a count [count]");
    v("demo_rate_hz", rate_hz, "a rate [Hz]");
    v("demo_enabled", enabled, "a switch");
    v("demo_mode", mode, "a choice", {"fast", "exact"});
    v("demo_start_ns", start_ns, "a time [ns]");
  }
};

void ExpectConfigError(OptionRegistry& registry, const std::string& yaml, const std::string& expected) {
  try {
    registry.LoadYamlString(yaml, "run.yaml");
    FAIL() << "expected a ConfigError containing '" << expected << "'";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
  }
}

TEST(OptionRegistry, LoadsYamlSectionsIntoFields) {
  DemoOptions demo;
  OptionRegistry registry;
  registry.Add("demo", &demo);
  registry.LoadYamlString("%YAML:1.0\ndemo:\n  demo_count: 12\n  demo_rate_hz: 200\n  demo_enabled: false\n"
                          "  demo_mode: exact\n  demo_start_ns: 1413393212225760512\n");
  EXPECT_EQ(demo.count, 12);
  EXPECT_EQ(demo.rate_hz, 200.0);
  EXPECT_FALSE(demo.enabled);
  EXPECT_EQ(demo.mode, "exact");
  EXPECT_EQ(demo.start_ns, 1413393212225760512LL);
}

TEST(OptionRegistry, RejectsUnknownKeysBadTypesAndBadChoicesWithFileAndLine) {
  DemoOptions demo;
  OptionRegistry registry;
  registry.Add("demo", &demo);
  ExpectConfigError(registry, "demo:\n  demo_cuont: 1\n", "run.yaml:2: unknown key 'demo_cuont'");
  ExpectConfigError(registry, "demos:\n  demo_count: 1\n", "run.yaml:1: unknown section 'demos'");
  ExpectConfigError(registry, "demo:\n  demo_count: 1.5\n", "run.yaml:2: 'demo_count': expected an integer");
  ExpectConfigError(registry, "demo:\n  demo_rate_hz: fast\n", "expected a finite number");
  ExpectConfigError(registry, "demo:\n  demo_rate_hz: .nan\n", "expected a finite number");
  ExpectConfigError(registry, "demo:\n\n  demo_mode: slow\n", "run.yaml:3: 'demo_mode': 'slow' is not one of fast|exact");
  ExpectConfigError(registry, "demo:\n  demo_enabled: maybe\n", "expected true or false");
  ExpectConfigError(registry, "demo: [1, 2]\n", "must be a map");
  EXPECT_THROW(registry.Set("no_such_option", "1"), ConfigError);
  EXPECT_THROW(registry.Set("demo_mode", "slow"), ConfigError);
}

struct RangedOptions {
  int size = 10;
  double sigma = 0.5;
  double fraction = 0.7;
  template <class V>
  void Visit(V& v) {
    v("ranged_size", size, "a size [count]", AtLeast(1));
    v("ranged_sigma", sigma, "a noise [px]", Positive());
    v("ranged_fraction", fraction, "a fraction []", Between(0, 1));
  }
};

TEST(OptionRegistry, RejectsValuesOutsideTheRangeNamingItAndTheKey) {
  RangedOptions ranged;
  OptionRegistry registry;
  registry.Add("ranged", &ranged);
  ExpectConfigError(registry, "ranged:\n  ranged_size: 0\n",
                    "run.yaml:2: 'ranged_size': '0' is outside the valid range [1, inf)");
  ExpectConfigError(registry, "ranged:\n  ranged_sigma: 0\n", "'ranged_sigma': '0' is outside the valid range (0, inf)");
  ExpectConfigError(registry, "ranged:\n  ranged_fraction: 1.5\n", "valid range [0, 1]");
  registry.Set("ranged_size", "1");
  registry.Set("ranged_sigma", "1e-9");
  registry.Set("ranged_fraction", "1");
  EXPECT_EQ(ranged.size, 1);
  EXPECT_EQ(ranged.fraction, 1.0);
  EXPECT_THROW(registry.Set("ranged_size", "-1"), ConfigError);
  EXPECT_THROW(registry.Set("ranged_sigma", "-0.5"), ConfigError);
  EXPECT_EQ(RangeText(Between(-1, 1)), "[-1, 1]");
}

TEST(OptionRegistry, RejectsRepeatedAndNonScalarSectionsAndKeys) {
  RangedOptions ranged;
  OptionRegistry registry;
  registry.Add("ranged", &ranged);
  ExpectConfigError(registry, "ranged:\n  ranged_size: 2\nranged:\n  ranged_size: 3\n",
                    "run.yaml:3: section 'ranged' appears twice (first on line 1)");
  ExpectConfigError(registry, "ranged:\n  ranged_size: 2\n  ranged_size: 3\n",
                    "run.yaml:3: key 'ranged_size' appears twice (first on line 2)");
  ExpectConfigError(registry, "ranged:\n  ranged_size: {a: 1}\n", "run.yaml:2: 'ranged_size' must be a single value");
  ExpectConfigError(registry, "[x]:\n  ranged_size: 2\n", "run.yaml:1: section names must be plain words");
}

TEST(OptionRegistry, FlagsOverrideYamlOnlyWhenGiven) {
  DemoOptions demo;
  OptionRegistry registry;
  registry.Add("demo", &demo);
  registry.RegisterFlags();
  registry.LoadYamlString("demo:\n  demo_count: 12\n  demo_rate_hz: 100\n");
  ASSERT_FALSE(gflags::SetCommandLineOption("demo_rate_hz", "42.5").empty());
  ASSERT_FALSE(gflags::SetCommandLineOption("demo_mode", "exact").empty());
  registry.ApplyFlags();
  EXPECT_EQ(demo.count, 12);  // from the file: its flag was not given
  EXPECT_EQ(demo.rate_hz, 42.5);
  EXPECT_EQ(demo.mode, "exact");
  gflags::CommandLineFlagInfo info;
  ASSERT_TRUE(gflags::GetCommandLineFlagInfo("demo_count", &info));
  EXPECT_EQ(info.default_value, "3");
  EXPECT_EQ(info.filename, "options/demo");
}

TEST(OptionRegistry, RoundTripsThroughItsOwnYaml) {
  EstimatorOptions options;
  options.policy.window_size = 30;
  options.model.pixel_sigma = 0.25;
  options.init.init = "groundtruth";
  OptionRegistry registry;
  registry.Add("policy", &options.policy);
  registry.Add("solver", &options.solver);
  registry.Add("model", &options.model);
  registry.Add("init", &options.init);
  const std::string yaml = registry.ToYaml();

  EstimatorOptions loaded;
  OptionRegistry other;
  other.Add("policy", &loaded.policy);
  other.Add("solver", &loaded.solver);
  other.Add("model", &loaded.model);
  other.Add("init", &loaded.init);
  other.LoadYamlString(yaml);
  EXPECT_EQ(loaded.policy.window_size, 30);
  EXPECT_EQ(loaded.model.pixel_sigma, 0.25);
  EXPECT_EQ(loaded.init.init, "groundtruth");
  EXPECT_EQ(other.ToYaml(), yaml);
}

}  // namespace
}  // namespace vio::tools
