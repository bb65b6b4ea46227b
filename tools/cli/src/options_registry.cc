#include "vio/cli/options_registry.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <deque>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include <gflags/gflags.h>
#include <glog/logging.h>
#include <yaml-cpp/yaml.h>

namespace vio::tools {
namespace {

std::string JoinChoices(const std::vector<std::string>& choices) {
  std::string out;
  for (const std::string& c : choices) out += (out.empty() ? "" : "|") + c;
  return out;
}

// Parses `text` into the field's type; returns an error message or "".
struct TextParser {
  const std::string& text;
  std::string operator()(bool* v) const {
    if (text == "true" || text == "1") { *v = true; return ""; }
    if (text == "false" || text == "0") { *v = false; return ""; }
    return "expected true or false, got '" + text + "'";
  }
  template <class Int>
  std::string ParseInt(Int* v) const {
    Int parsed{};
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), parsed);
    if (ec != std::errc() || end != text.data() + text.size()) return "expected an integer, got '" + text + "'";
    *v = parsed;
    return "";
  }
  std::string operator()(int* v) const { return ParseInt(v); }
  std::string operator()(std::int64_t* v) const { return ParseInt(v); }
  std::string operator()(double* v) const {
    double parsed = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), parsed);
    if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(parsed)) {
      return "expected a finite number, got '" + text + "'";
    }
    *v = parsed;
    return "";
  }
  std::string operator()(std::string* v) const { *v = text; return ""; }
};

std::string FieldToText(const OptionField& f) {
  return std::visit(
      [](auto* v) -> std::string {
        using T = std::decay_t<decltype(*v)>;
        if constexpr (std::is_same_v<T, bool>) return *v ? "true" : "false";
        else if constexpr (std::is_same_v<T, std::string>) return *v;
        else if constexpr (std::is_same_v<T, double>) {
          std::ostringstream os;
          os.precision(17);
          os << *v;
          return os.str();
        } else return std::to_string(*v);
      },
      f.value);
}

bool InRange(const OptionRange& range, double value) {
  return value <= range.max && (range.min_exclusive ? value > range.min : value >= range.min);
}

// The field's value as a number (nothing for strings).
std::optional<double> NumericValue(const OptionField& f) {
  return std::visit(
      [](auto* v) -> std::optional<double> {
        using T = std::decay_t<decltype(*v)>;
        if constexpr (std::is_arithmetic_v<T>) return static_cast<double>(*v);
        else return std::nullopt;
      },
      f.value);
}

// Assigns `text` to `field`, checking its type, choices and range.
std::string AssignText(OptionField& field, const std::string& text) {
  if (!field.choices.empty() &&
      std::find(field.choices.begin(), field.choices.end(), text) == field.choices.end()) {
    return "'" + text + "' is not one of " + JoinChoices(field.choices);
  }
  if (std::string error = std::visit(TextParser{text}, field.value); !error.empty()) return error;
  const std::optional<double> value = NumericValue(field);
  if (field.range && value && !InRange(*field.range, *value)) {
    return "'" + text + "' is outside the valid range " + RangeText(*field.range);
  }
  return "";
}

// A map's keys as text, each once: ConfigError naming the line of a
// non-scalar or repeated key.
template <class Where>
std::vector<std::pair<YAML::Node, YAML::Node>> UniqueEntries(const YAML::Node& map, const std::string& what,
                                                             const Where& where) {
  std::vector<std::pair<YAML::Node, YAML::Node>> entries;
  std::map<std::string, int> first_line;
  for (const auto& entry : map) {
    if (!entry.first.IsScalar()) throw ConfigError(where(entry.first) + what + " names must be plain words");
    const std::string name = entry.first.Scalar();
    const auto [it, inserted] = first_line.emplace(name, entry.first.Mark().line + 1);
    if (!inserted) {
      throw ConfigError(where(entry.first) + what + " '" + name + "' appears twice (first on line " +
                        std::to_string(it->second) + ")");
    }
    entries.emplace_back(entry.first, entry.second);
  }
  return entries;
}

// Storage of the gflags flags: gflags keeps pointers, so it must never move.
struct FlagStorage {
  std::deque<bool> bools;
  std::deque<gflags::int32> ints;
  std::deque<gflags::int64> int64s;
  std::deque<double> doubles;
  std::deque<std::string> strings;
  std::deque<std::string> texts;  // names and help strings
};

FlagStorage& Storage() {
  static FlagStorage* storage = new FlagStorage();
  return *storage;
}

template <class T>
void RegisterOne(std::deque<T>& store, const OptionField& f, T value) {
  FlagStorage& s = Storage();
  const char* name = s.texts.emplace_back(f.name).c_str();
  std::string help_text = f.doc;
  if (!f.choices.empty()) help_text += " {" + JoinChoices(f.choices) + "}";
  if (f.range) help_text += " valid: " + RangeText(*f.range);
  const char* help = s.texts.emplace_back(help_text).c_str();
  const char* file = s.texts.emplace_back("options/" + f.section).c_str();
  T* current = &store.emplace_back(value);
  T* default_value = &store.emplace_back(value);
  gflags::FlagRegisterer(name, help, file, current, default_value);
}

}  // namespace

std::string RangeText(const OptionRange& range) {
  const auto number = [](double x) {
    if (std::isinf(x)) return std::string(x > 0 ? "inf" : "-inf");
    std::ostringstream os;
    os << x;
    return os.str();
  };
  return (range.min_exclusive ? "(" : "[") + number(range.min) + ", " + number(range.max) +
         (std::isinf(range.max) ? ")" : "]");
}

void OptionRegistry::AddField(OptionField field) {
  CHECK(Find(field.name) == nullptr) << "option '" << field.name << "' is registered twice";
  fields_.push_back(std::move(field));
}

OptionField* OptionRegistry::Find(const std::string& name) {
  for (OptionField& f : fields_) {
    if (f.name == name) return &f;
  }
  return nullptr;
}

void OptionRegistry::Set(const std::string& name, const std::string& text) {
  OptionField* field = Find(name);
  if (field == nullptr) throw ConfigError("unknown option '" + name + "'");
  if (std::string error = AssignText(*field, text); !error.empty()) {
    throw ConfigError("option '" + name + "': " + error);
  }
}

void OptionRegistry::LoadYamlFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path + ": cannot open configuration file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  LoadYamlString(buffer.str(), path);
}

void OptionRegistry::LoadYamlString(const std::string& input, const std::string& origin) {
  std::string text = input;
  // OpenCV FileStorage files start with "%YAML:1.0", which yaml-cpp rejects:
  // blank the line out so line numbers stay right.
  if (text.rfind("%YAML:", 0) == 0) text.replace(0, text.find('\n'), "");
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw ConfigError(origin + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  if (root.IsNull()) return;
  auto where = [&](const YAML::Node& n) { return origin + ":" + std::to_string(n.Mark().line + 1) + ": "; };
  if (!root.IsMap()) throw ConfigError(where(root) + "expected sections (a map) at top level");
  for (const auto& [section_key, section] : UniqueEntries(root, "section", where)) {
    const std::string section_name = section_key.Scalar();
    const bool known = std::any_of(fields_.begin(), fields_.end(),
                                   [&](const OptionField& f) { return f.section == section_name; });
    if (!known) throw ConfigError(where(section_key) + "unknown section '" + section_name + "'");
    if (!section.IsMap()) {
      throw ConfigError(where(section_key) + "section '" + section_name + "' must be a map of key: value");
    }
    for (const auto& [key_node, value] : UniqueEntries(section, "key", where)) {
      const std::string key = key_node.Scalar();
      OptionField* field = Find(key);
      if (field == nullptr || field->section != section_name) {
        throw ConfigError(where(key_node) + "unknown key '" + key + "' in section '" + section_name + "'");
      }
      if (!value.IsScalar()) throw ConfigError(where(key_node) + "'" + key + "' must be a single value");
      if (std::string error = AssignText(*field, value.Scalar()); !error.empty()) {
        throw ConfigError(where(value) + "'" + key + "': " + error);
      }
    }
  }
}

void OptionRegistry::RegisterFlags() const {
  FlagStorage& s = Storage();
  for (const OptionField& f : fields_) {
    std::visit(
        [&](auto* v) {
          using T = std::decay_t<decltype(*v)>;
          if constexpr (std::is_same_v<T, bool>) RegisterOne(s.bools, f, *v);
          else if constexpr (std::is_same_v<T, int>) RegisterOne<gflags::int32>(s.ints, f, *v);
          else if constexpr (std::is_same_v<T, std::int64_t>) RegisterOne<gflags::int64>(s.int64s, f, *v);
          else if constexpr (std::is_same_v<T, double>) RegisterOne(s.doubles, f, *v);
          else RegisterOne(s.strings, f, *v);
        },
        f.value);
  }
}

void OptionRegistry::ApplyFlags() {
  for (OptionField& f : fields_) {
    gflags::CommandLineFlagInfo info;
    if (!gflags::GetCommandLineFlagInfo(f.name.c_str(), &info) || info.is_default) continue;
    if (std::string error = AssignText(f, info.current_value); !error.empty()) {
      throw ConfigError("--" + f.name + ": " + error);
    }
  }
}

std::string OptionRegistry::ToYaml() const {
  std::ostringstream os;
  std::string section;
  for (const OptionField& f : fields_) {
    if (f.section != section) {
      section = f.section;
      os << section << ":\n";
    }
    std::string value = FieldToText(f);
    if (std::holds_alternative<std::string*>(f.value)) value = "\"" + value + "\"";
    os << "  " << f.name << ": " << value << "  # " << f.doc << "\n";
  }
  return os.str();
}

}  // namespace vio::tools
