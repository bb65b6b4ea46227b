#include "vio/cli/run_config.h"

namespace vio::tools {

void BindRunConfig(RunConfig* config, OptionRegistry* registry) {
  registry->Add("calibration", &config->calibration);
  registry->Add("bag", &config->bag);
  registry->Add("frontend", &config->frontend);
  registry->Add("policy", &config->estimator.policy);
  registry->Add("msckf", &config->estimator.msckf);
  registry->Add("persistent", &config->estimator.persistent);
  registry->Add("local_map", &config->estimator.local_map);
  registry->Add("batch", &config->estimator.batch);
  registry->Add("smoother", &config->estimator.smoother);
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

void ValidateRunConfig(const RunConfig& config) {
  const PolicyOptions& policy = config.estimator.policy;
  const bool msckf_like = policy.policy == "msckf" || policy.policy == "fixed_lag";
  if (msckf_like && policy.window_size < 2) {
    throw ConfigError("--window_size=" + std::to_string(policy.window_size) + ": the " + policy.policy +
                      " policy needs a window of at least 2 states");
  }
  const bool windowed = msckf_like || policy.policy == "swf";
  const int keyframes = config.estimator.local_map.local_map_keyframes;
  if (keyframes > 0 && policy.policy != "swf" && policy.policy != "msckf") {
    throw ConfigError("--local_map_keyframes=" + std::to_string(keyframes) +
                      ": the local map is for the policies swf and msckf, not " + policy.policy);
  }
  if (keyframes > 0 && policy.window_size < 2) {
    throw ConfigError("--local_map_keyframes=" + std::to_string(keyframes) +
                      ": the local map needs --window_size of at least 2 (the frames it keeps behind the newest)");
  }
  if (keyframes > 0 && config.estimator.persistent.persistent_landmarks > 0) {
    throw ConfigError("--local_map_keyframes=" + std::to_string(keyframes) +
                      " with --persistent_landmarks: the local map keeps its landmarks itself; use one of them");
  }
  if (config.estimator.persistent.persistent_landmarks > 0 && !windowed) {
    throw ConfigError("--persistent_landmarks=" + std::to_string(config.estimator.persistent.persistent_landmarks) +
                      ": long-lived landmarks are for the policies swf, msckf and fixed_lag, not " + policy.policy);
  }
}

RunConfig LoadRunConfig(const std::string& yaml_path) {
  RunConfig config;
  OptionRegistry registry;
  BindRunConfig(&config, &registry);
  if (!yaml_path.empty()) registry.LoadYamlFile(yaml_path);
  registry.ApplyFlags();
  ValidateRunConfig(config);
  return config;
}

std::string RunConfigToYaml(RunConfig config) {
  OptionRegistry registry;
  BindRunConfig(&config, &registry);
  return registry.ToYaml();
}

}  // namespace vio::tools
