#pragma once
// Builds a text file in memory, then saves it in one write: deterministic
// output, doubles in their shortest round-trip form (std::to_chars), so that
// parsing the text gives back the very same double.
#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace vio::tools {

class TextWriter {
 public:
  /// `path` is where Save() writes; it also names the file in errors.
  explicit TextWriter(std::string path) : path_(std::move(path)) {}

  TextWriter& Int(std::int64_t value);
  /// Shortest text that parses back to exactly `value`; throws DatasetError
  /// for NaN or inf (the readers reject them, so they are never written).
  TextWriter& Double(double value);
  /// Double(), always spelled as a real ("1.0", not "1") so that typed YAML
  /// readers (OpenCV FileStorage, PyYAML) see a float.
  TextWriter& Real(double value);
  /// Nanoseconds as decimal seconds with 9 fraction digits ("12.000000500").
  TextWriter& DecimalSeconds(std::int64_t t_ns);
  TextWriter& Text(std::string_view text);
  /// A CSV header line: '#' then the column names joined by ','.
  TextWriter& Header(const std::vector<std::string>& columns);

  const std::string& text() const { return text_; }
  const std::string& path() const { return path_; }

  /// Writes the text to path(), creating its parent folders. Throws
  /// DatasetError "<path>: cannot write" on failure.
  void Save() const;

 private:
  std::string path_;
  std::string text_;
};

}  // namespace vio::tools
