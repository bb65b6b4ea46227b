#include "vio/cli/run_config.h"

namespace vio::tools {

void BindRunConfig(RunConfig* config, OptionRegistry* registry) {
  registry->Add("calibration", &config->calibration);
  registry->Add("bag", &config->bag);
  registry->Add("frontend", &config->frontend);
  registry->Add("policy", &config->estimator.policy);
  registry->Add("msckf", &config->estimator.msckf);
  registry->Add("batch", &config->estimator.batch);
  registry->Add("solver", &config->estimator.solver);
  registry->Add("model", &config->estimator.model);
  registry->Add("init", &config->estimator.init);
}

void RegisterRunConfigFlags() {
  RunConfig defaults;
  OptionRegistry registry;
  BindRunConfig(&defaults, &registry);
  registry.RegisterFlags();
}

RunConfig LoadRunConfig(const std::string& yaml_path) {
  RunConfig config;
  OptionRegistry registry;
  BindRunConfig(&config, &registry);
  if (!yaml_path.empty()) registry.LoadYamlFile(yaml_path);
  registry.ApplyFlags();
  return config;
}

std::string RunConfigToYaml(RunConfig config) {
  OptionRegistry registry;
  BindRunConfig(&config, &registry);
  return registry.ToYaml();
}

}  // namespace vio::tools
