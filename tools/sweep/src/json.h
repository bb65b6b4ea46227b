#pragma once
// A small strict JSON reader for the summary.json files `vio run` writes
// (no JSON library is among the project's dependencies). Private to tools.
#include <string>
#include <vector>

namespace vio::tools {

struct JsonValue {
  enum class Type { kNull, kBool, kNumber, kString, kArray, kObject };
  Type type = Type::kNull;
  bool boolean = false;
  double number = 0.0;
  std::string string;
  std::vector<JsonValue> items;     ///< array elements, or object values
  std::vector<std::string> keys;    ///< object keys (parallel to items)

  /// The member `key` of an object; nullptr when absent or not an object.
  const JsonValue* Find(const std::string& key) const;
  /// The number, NaN for null; throws std::runtime_error for other types.
  double AsNumber() const;
};

/// Parses one JSON document. Throws std::runtime_error "<origin>: offset N: ..."
/// on malformed text.
JsonValue ParseJson(const std::string& text, const std::string& origin);

}  // namespace vio::tools
