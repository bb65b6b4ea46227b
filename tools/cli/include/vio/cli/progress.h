#pragma once
// A one-line progress bar for long runs, shown only on a terminal: when the
// output is piped or redirected it prints nothing.
#include <chrono>
#include <cstdint>
#include <iosfwd>
#include <string>

namespace vio::tools {

class ProgressBar {
 public:
  /// Draws on stderr when stderr is a terminal.
  ProgressBar(std::int64_t total, std::string unit);
  /// Draws on `out` when `enabled` (tests).
  ProgressBar(std::int64_t total, std::string unit, std::ostream* out, bool enabled);
  ~ProgressBar();

  /// Sets the number of finished items; redraws at most every 100 ms.
  void Update(std::int64_t done);
  /// Draws 100 % and ends the line.
  void Finish();
  /// Ends the line where the bar is (a run stopped before the end).
  void Stop();
  /// Text after the count (a long solve's iteration and cost), drawn now; empty removes it.
  void SetNote(std::string note);
  /// Blanks the bar's line (a log line is then written in its place; the next draw is below it).
  void ClearLine();

 private:
  void Draw();

  std::int64_t total_;
  std::int64_t done_ = 0;
  std::string unit_;
  std::string note_;
  size_t drawn_length_ = 0;  ///< of the last line drawn (a shorter one is padded over it)
  std::ostream* out_;
  bool enabled_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
};

}  // namespace vio::tools
