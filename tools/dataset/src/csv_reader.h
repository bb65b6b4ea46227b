#pragma once
// A small, strict reader of delimiter-separated text tables (EuRoC CSV, TUM
// text), and the exact number parsers it shares with the YAML readers.
//
// Lines starting with '#' and blank lines are skipped; CRLF and LF endings
// and a UTF-8 byte-order mark are accepted; fields are trimmed of spaces and
// tabs. Every error is a DatasetError "<path>:<line>: <what>" (1-based line).
// Integers are parsed as integers (never through double), doubles with
// std::from_chars (correctly rounded), so reading is fast and exact.
#include <cstdint>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "vio/estimator/types.h"
#include "vio/dataset/euroc_dataset.h"

namespace vio::tools {

/// The error "<path>:<line>: <what>" (1-based line) every reader throws.
DatasetError LineError(const std::string& path, int line, const std::string& what);

/// The whole of `text` as a base-10 int64; false when it is not one (or out of range).
bool ParseInt64(std::string_view text, std::int64_t* value);

/// The whole of `text` as a double (an optional leading '+' allowed; "nan" and
/// "inf" parse, callers check finiteness); false when it is not a number.
bool ParseDouble(std::string_view text, double* value);

/// Decimal seconds ("1403715274.30214", "-2.5", "12") to integer nanoseconds,
/// exactly (digits past the 9th round half up); false when malformed or out of range.
bool ParseDecimalSecondsToNanos(std::string_view text, Timestamp* t_ns);

/// Reads one table file row by row; see the file comment for the format.
class CsvReader {
 public:
  enum class Separator {
    kComma,       ///< ',' between fields (EuRoC CSV)
    kWhitespace,  ///< runs of spaces/tabs between fields (TUM text)
  };

  /// Loads `path` for rows of `columns.size()` fields named `columns` (the
  /// names appear in error messages). Throws DatasetError "<path>: cannot open".
  CsvReader(std::string path, std::vector<std::string> columns,
            Separator separator = Separator::kComma);

  /// Advances to the next data row; false at the end of the file. Throws when
  /// the row has the wrong number of fields (the message says expected vs got).
  bool NextRow();

  const std::string& path() const { return path_; }
  int line() const { return line_; }       ///< 1-based line of the current row
  int row_count() const { return rows_; }  ///< data rows read so far

  std::string_view Field(int column) const;
  /// The field as an int64; throws quoting it when it is not one.
  std::int64_t Int64(int column) const;
  /// The field as a finite double; throws quoting it when non-numeric, NaN or inf.
  double Double(int column) const;
  /// As Double, and throws quoting it when its magnitude exceeds `max_abs`
  /// (`what` says why, e.g. "a physical IMU reading").
  double BoundedDouble(int column, double max_abs, const std::string& what) const;
  /// The field as decimal seconds, converted exactly to nanoseconds.
  Timestamp DecimalSeconds(int column) const;

  /// Throws DatasetError "<path>:<line>: <what>" for the current line.
  [[noreturn]] void Fail(const std::string& what) const;
  /// Throws "<path>:<line>: empty: no data rows" when no row was read.
  void RequireRows() const;

 private:
  std::string ColumnName(int column) const;
  void SplitCurrentLine(std::string_view line);

  std::string path_;
  std::vector<std::string> columns_;
  Separator separator_;
  std::ifstream in_;   ///< read line by line: a table is never held whole
  std::string text_;  ///< the current line (fields_ view into it)
  int line_ = 0;
  int rows_ = 0;
  std::vector<std::string_view> fields_;
};

/// Checks, row by row, that timestamps increase (strictly, or non-decreasing
/// when `allow_equal`); the error names the offending and the previous line.
class TimestampOrder {
 public:
  explicit TimestampOrder(bool allow_equal = false) : allow_equal_(allow_equal) {}
  void Check(const CsvReader& reader, Timestamp t_ns);

 private:
  bool allow_equal_;
  std::optional<Timestamp> last_t_ns_;
  int last_line_ = 0;
};

}  // namespace vio::tools
