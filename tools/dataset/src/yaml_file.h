#pragma once
// Typed, checked access to the nodes of one YAML file, shared by the EuRoC sensor.yaml and the
// Kalibr readers (not public API). Every error is a DatasetError "<path>:<line>: <what>".
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "csv_reader.h"
#include "euroc_internal.h"

namespace vio::tools {

// Typed, checked access to the nodes of one YAML file; errors name the file
// and the line of the node concerned.
class YamlFile {
 public:
  explicit YamlFile(std::string path) : path_(std::move(path)), root_(LoadSensorYaml(path_)) {
    if (!root_.IsMap()) throw LineError(path_, 1, "expected a YAML map of keys");
  }

  const YAML::Node& root() const { return root_; }
  const std::string& path() const { return path_; }

  [[noreturn]] void Fail(const YAML::Node& node, const std::string& what) const {
    const int line = node.Mark().is_null() ? 1 : node.Mark().line + 1;
    throw LineError(path_, line, what);
  }

  YAML::Node Require(const YAML::Node& map, const std::string& key) const {
    YAML::Node value = map[key];
    if (!value.IsDefined() || value.IsNull()) Fail(map, "missing key '" + key + "'");
    return value;
  }

  std::string String(const YAML::Node& map, const std::string& key) const {
    const YAML::Node node = Require(map, key);
    if (!node.IsScalar()) Fail(node, "'" + key + "' must be a single value");
    return node.Scalar();
  }

  double Number(const YAML::Node& node, const std::string& what) const {
    double value = 0.0;
    if (!node.IsScalar() || !ParseDouble(node.Scalar(), &value)) {
      Fail(node, "'" + what + "' is not a number" + Quoted(node));
    }
    if (!std::isfinite(value)) Fail(node, "'" + what + "' is not finite" + Quoted(node));
    return value;
  }

  double Positive(const YAML::Node& map, const std::string& key) const {
    const YAML::Node node = Require(map, key);
    const double value = Number(node, key);
    if (!(value > 0.0)) Fail(node, "'" + key + "' must be positive" + Quoted(node));
    return value;
  }

  std::int64_t Integer(const YAML::Node& node, const std::string& what) const {
    std::int64_t value = 0;
    if (!node.IsScalar() || !ParseInt64(node.Scalar(), &value)) {
      Fail(node, "'" + what + "' is not an integer" + Quoted(node));
    }
    return value;
  }

  std::vector<double> Numbers(const YAML::Node& map, const std::string& key,
                              std::size_t expected) const {
    const YAML::Node node = Require(map, key);
    if (!node.IsSequence() || node.size() != expected) {
      Fail(node, "'" + key + "' must be a list of " + std::to_string(expected) + " numbers, got " +
                     (node.IsSequence() ? std::to_string(node.size()) + " values" : "no list"));
    }
    std::vector<double> values;
    for (std::size_t i = 0; i < expected; ++i) {
      values.push_back(Number(node[i], key + "[" + std::to_string(i) + "]"));
    }
    return values;
  }

 private:
  static std::string Quoted(const YAML::Node& node) {
    return node.IsScalar() ? ": \"" + node.Scalar() + "\"" : "";
  }

  std::string path_;
  YAML::Node root_;
};

}  // namespace vio::tools
