#pragma once
// One place that knows every option of a run: it loads them from the run's
// YAML file (sections named after components), lets a gflags flag of the same
// name override each one, validates choices, and writes the effective
// configuration back out.
//
// An Options struct takes part by listing its fields once:
//
//   struct SwfOptions {
//     int window_size = 10;
//     template <class V> void Visit(V& v) {
//       v("window_size", window_size, "states kept in the window [frames]");
//     }
//   };
//
// String fields may list their allowed values: v("policy", policy, "doc", {"swf", "msckf"});
// numeric fields their valid range: v("window_size", window_size, "doc", AtLeast(1)).
#include <memory>
#include <optional>
#include <stdexcept>
#include <type_traits>
#include <string>
#include <variant>
#include <vector>

#include "vio/estimator/option_range.h"

namespace vio::tools {

/// Bad configuration: unknown key, wrong type, value not among the choices.
/// The message names the file and line where there is one.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One option: where it lives and what it means.
struct OptionField {
  std::string section;  ///< YAML section, e.g. "estimator"
  std::string name;     ///< YAML key and flag name, unique across sections
  std::string doc;      ///< one line with units
  std::variant<bool*, int*, std::int64_t*, double*, std::string*> value;
  std::vector<std::string> choices;  ///< allowed values of a string option; empty = any
  std::optional<OptionRange> range;  ///< valid values of a numeric option; none = any
};

/// "[1, inf)", "(0, 1]": the range as shown in messages and --help.
std::string RangeText(const OptionRange& range);

class OptionRegistry {
 public:
  /// Adds every field of `options` (which must outlive the registry) under `section`.
  template <class Options>
  void Add(const std::string& section, Options* options) {
    Collector collector{section, this};
    options->Visit(collector);
  }

  /// Sets fields from a YAML file: top-level keys are sections, their keys are
  /// fields. Unknown, duplicated or non-scalar sections or keys, wrong types,
  /// bad choices and values outside the range are errors (ConfigError naming
  /// file:line and key). A `%YAML:1.0` first line is accepted.
  void LoadYamlFile(const std::string& path);
  void LoadYamlString(const std::string& text, const std::string& origin = "<string>");

  /// Sets `name` from text (as a flag would); ConfigError when unknown or invalid.
  void Set(const std::string& name, const std::string& text);

  /// Registers one gflags flag per field (default = the field's current value).
  /// Call before gflags::ParseCommandLineFlags; names must not clash with other flags.
  void RegisterFlags() const;

  /// Copies the value of every flag given on the command line into its field.
  void ApplyFlags();

  /// The effective configuration as YAML (sections in registration order).
  std::string ToYaml() const;

  const std::vector<OptionField>& fields() const { return fields_; }

 private:
  struct Collector {
    std::string section;
    OptionRegistry* registry;
    template <class T>
    void operator()(const char* name, T& value, const char* doc,
                    std::vector<std::string> choices = {}) {
      registry->AddField(OptionField{section, name, doc, &value, std::move(choices), std::nullopt});
    }
    template <class T>
    void operator()(const char* name, T& value, const char* doc, OptionRange range) {
      static_assert(std::is_arithmetic_v<T>, "a range needs a numeric option");
      registry->AddField(OptionField{section, name, doc, &value, {}, range});
    }
  };
  void AddField(OptionField field);
  OptionField* Find(const std::string& name);

  std::vector<OptionField> fields_;
};

}  // namespace vio::tools
