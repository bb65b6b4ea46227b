#include <glog/logging.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <utility>

#include "csv_reader.h"

namespace vio::tools {
namespace {

constexpr std::int64_t kNanosPerSecond = 1'000'000'000;

bool IsBlank(char c) { return c == ' ' || c == '\t'; }

std::string_view Trim(std::string_view s) {
  while (!s.empty() && IsBlank(s.front())) s.remove_prefix(1);
  while (!s.empty() && IsBlank(s.back())) s.remove_suffix(1);
  return s;
}

bool AllDigits(std::string_view s) {
  for (const char c : s) {
    if (c < '0' || c > '9') return false;
  }
  return true;
}

// The digits of a fraction as nanoseconds: the first 9 digits, rounded half
// up on the 10th.
std::int64_t FractionToNanos(std::string_view digits) {
  std::int64_t nanos = 0;
  for (std::size_t i = 0; i < 9; ++i) {
    nanos = nanos * 10 + (i < digits.size() ? digits[i] - '0' : 0);
  }
  if (digits.size() > 9 && digits[9] >= '5') ++nanos;
  return nanos;
}

}  // namespace

DatasetError LineError(const std::string& path, int line, const std::string& what) {
  return DatasetError(path + ":" + std::to_string(line) + ": " + what);
}

bool ParseInt64(std::string_view text, std::int64_t* value) {
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, *value);
  return !text.empty() && ec == std::errc() && ptr == end;
}

bool ParseDouble(std::string_view text, double* value) {
  if (text.size() > 1 && text[0] == '+' && text[1] != '-') text.remove_prefix(1);
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, *value);
  return !text.empty() && ec == std::errc() && ptr == end;
}

bool ParseDecimalSecondsToNanos(std::string_view text, Timestamp* t_ns) {
  bool negative = false;
  if (!text.empty() && (text[0] == '-' || text[0] == '+')) {
    negative = text[0] == '-';
    text.remove_prefix(1);
  }
  const std::size_t dot = text.find('.');
  const std::string_view whole = text.substr(0, dot);
  const std::string_view fraction = dot == std::string_view::npos ? "" : text.substr(dot + 1);
  if ((whole.empty() && fraction.empty()) || !AllDigits(whole) || !AllDigits(fraction)) {
    return false;
  }
  std::int64_t seconds = 0;
  if (!whole.empty() && !ParseInt64(whole, &seconds)) return false;
  const std::int64_t nanos = FractionToNanos(fraction);
  if (seconds > (std::numeric_limits<std::int64_t>::max() - nanos) / kNanosPerSecond) return false;
  const std::int64_t total = seconds * kNanosPerSecond + nanos;
  *t_ns = negative ? -total : total;
  return true;
}

CsvReader::CsvReader(std::string path, std::vector<std::string> columns, Separator separator)
    : path_(std::move(path)), columns_(std::move(columns)), separator_(separator) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path_, ec)) {
    throw DatasetError(path_ + ": cannot open (missing or not a file)");
  }
  in_.open(path_, std::ios::binary);
  if (!in_) throw DatasetError(path_ + ": cannot open");
  fields_.reserve(columns_.size());
}

bool CsvReader::NextRow() {
  while (std::getline(in_, text_)) {
    std::string_view line(text_);
    constexpr std::string_view kUtf8Bom = "\xEF\xBB\xBF";
    if (line_ == 0 && line.substr(0, kUtf8Bom.size()) == kUtf8Bom) line.remove_prefix(kUtf8Bom.size());
    ++line_;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    line = Trim(line);
    if (line.empty() || line.front() == '#') continue;
    SplitCurrentLine(line);
    if (fields_.size() != columns_.size()) {
      Fail("wrong column count: expected " + std::to_string(columns_.size()) + ", got " +
           std::to_string(fields_.size()));
    }
    ++rows_;
    return true;
  }
  if (in_.bad()) throw DatasetError(path_ + ": read error");
  return false;
}

void CsvReader::SplitCurrentLine(std::string_view line) {
  fields_.clear();
  if (separator_ == Separator::kComma) {
    while (true) {
      const std::size_t comma = line.find(',');
      fields_.push_back(Trim(line.substr(0, comma)));
      if (comma == std::string_view::npos) return;
      line.remove_prefix(comma + 1);
    }
  }
  std::size_t i = 0;
  while (i < line.size()) {
    const std::size_t start = i;
    while (i < line.size() && !IsBlank(line[i])) ++i;
    fields_.push_back(line.substr(start, i - start));
    while (i < line.size() && IsBlank(line[i])) ++i;
  }
}

std::string_view CsvReader::Field(int column) const {
  CHECK_GE(column, 0);
  CHECK_LT(static_cast<std::size_t>(column), fields_.size());
  return fields_[column];
}

std::string CsvReader::ColumnName(int column) const {
  return "column " + std::to_string(column + 1) + " (" + columns_[column] + ")";
}

std::int64_t CsvReader::Int64(int column) const {
  const std::string_view field = Field(column);
  std::int64_t value = 0;
  if (!ParseInt64(field, &value)) {
    Fail(ColumnName(column) + ": not an integer: \"" + std::string(field) + "\"");
  }
  return value;
}

double CsvReader::Double(int column) const {
  const std::string_view field = Field(column);
  double value = 0.0;
  if (!ParseDouble(field, &value)) {
    Fail(ColumnName(column) + ": non-numeric field \"" + std::string(field) + "\"");
  }
  if (!std::isfinite(value)) {
    Fail(ColumnName(column) + ": non-finite value (NaN or inf) \"" + std::string(field) + "\"");
  }
  return value;
}

double CsvReader::BoundedDouble(int column, double max_abs, const std::string& what) const {
  const double value = Double(column);
  if (std::abs(value) > max_abs) {
    std::ostringstream bound;
    bound << max_abs;
    Fail(ColumnName(column) + ": \"" + std::string(Field(column)) + "\" is beyond " + what + " (|value| <= " +
         bound.str() + ")");
  }
  return value;
}

Timestamp CsvReader::DecimalSeconds(int column) const {
  const std::string_view field = Field(column);
  Timestamp t_ns = 0;
  if (!ParseDecimalSecondsToNanos(field, &t_ns)) {
    Fail(ColumnName(column) + ": not decimal seconds: \"" + std::string(field) + "\"");
  }
  return t_ns;
}

void CsvReader::Fail(const std::string& what) const {
  throw LineError(path_, std::max(line_, 1), what);
}

void CsvReader::RequireRows() const {
  if (rows_ == 0) Fail("empty: no data rows");
}

void TimestampOrder::Check(const CsvReader& reader, Timestamp t_ns) {
  if (last_t_ns_.has_value() && (t_ns < *last_t_ns_ || (t_ns == *last_t_ns_ && !allow_equal_))) {
    // The message is built only for a failing row (one row per observation: this runs once per CSV line).
    const std::string previous = std::to_string(*last_t_ns_) + " on line " + std::to_string(last_line_);
    if (t_ns == *last_t_ns_) {
      reader.Fail("duplicated timestamp " + std::to_string(t_ns) + " (same as " + previous + ")");
    }
    reader.Fail("non-increasing timestamp " + std::to_string(t_ns) + " (after " + previous + ")");
  }
  last_t_ns_ = t_ns;
  last_line_ = reader.line();
}

}  // namespace vio::tools
