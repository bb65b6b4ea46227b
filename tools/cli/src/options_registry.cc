#include "vio/cli/options_registry.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <deque>
#include <fstream>
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

// Assigns `text` to `field`, checking its type and choices.
std::string AssignText(OptionField& field, const std::string& text) {
  if (!field.choices.empty() &&
      std::find(field.choices.begin(), field.choices.end(), text) == field.choices.end()) {
    return "'" + text + "' is not one of " + JoinChoices(field.choices);
  }
  return std::visit(TextParser{text}, field.value);
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
  const char* help = s.texts.emplace_back(help_text).c_str();
  const char* file = s.texts.emplace_back("options/" + f.section).c_str();
  T* current = &store.emplace_back(value);
  T* default_value = &store.emplace_back(value);
  gflags::FlagRegisterer(name, help, file, current, default_value);
}

}  // namespace

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
  for (const auto& section : root) {
    const std::string section_name = section.first.as<std::string>();
    const bool known = std::any_of(fields_.begin(), fields_.end(),
                                   [&](const OptionField& f) { return f.section == section_name; });
    if (!known) throw ConfigError(where(section.first) + "unknown section '" + section_name + "'");
    if (!section.second.IsMap()) throw ConfigError(where(section.first) + "section '" + section_name + "' must be a map");
    for (const auto& entry : section.second) {
      const std::string key = entry.first.as<std::string>();
      OptionField* field = Find(key);
      if (field == nullptr || field->section != section_name) {
        throw ConfigError(where(entry.first) + "unknown key '" + key + "' in section '" + section_name + "'");
      }
      if (!entry.second.IsScalar()) throw ConfigError(where(entry.second) + "'" + key + "' must be a scalar");
      if (std::string error = AssignText(*field, entry.second.Scalar()); !error.empty()) {
        throw ConfigError(where(entry.second) + "'" + key + "': " + error);
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
