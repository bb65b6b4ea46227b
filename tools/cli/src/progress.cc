#include "vio/cli/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <iostream>

namespace vio::tools {

ProgressBar::ProgressBar(std::int64_t total, std::string unit)
    : ProgressBar(total, std::move(unit), &std::cerr, isatty(fileno(stderr)) != 0) {}

ProgressBar::ProgressBar(std::int64_t total, std::string unit, std::ostream* out, bool enabled)
    : total_(std::max<std::int64_t>(total, 1)),
      unit_(std::move(unit)),
      out_(out),
      enabled_(enabled),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

ProgressBar::~ProgressBar() {
  if (enabled_ && !finished_) *out_ << "\n" << std::flush;
}

void ProgressBar::Update(std::int64_t done) {
  done_ = std::clamp<std::int64_t>(done, 0, total_);
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  Draw();
}

void ProgressBar::Finish() {
  done_ = total_;
  if (!enabled_ || finished_) return;
  Draw();
  *out_ << "\n" << std::flush;
  finished_ = true;
}

void ProgressBar::Stop() {
  if (!enabled_ || finished_) return;
  note_.clear();
  Draw();
  *out_ << "\n" << std::flush;
  finished_ = true;
}

void ProgressBar::ClearLine() {
  if (!enabled_ || finished_ || drawn_length_ == 0) return;
  *out_ << "\r" << std::string(drawn_length_, ' ') << "\r" << std::flush;
  drawn_length_ = 0;
}

void ProgressBar::SetNote(std::string note) {
  note_ = std::move(note);
  if (!enabled_ || finished_) return;
  last_draw_ = std::chrono::steady_clock::now();
  Draw();
}

void ProgressBar::Draw() {
  constexpr int kWidth = 30;
  const double fraction = static_cast<double>(done_) / static_cast<double>(total_);
  const int filled = static_cast<int>(fraction * kWidth);
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  char line[160];
  std::snprintf(line, sizeof(line), "\r[%-*s] %3d%% %lld/%lld %s %.1fs", kWidth,
                std::string(filled, '#').c_str(), static_cast<int>(fraction * 100.0),
                static_cast<long long>(done_), static_cast<long long>(total_), unit_.c_str(), elapsed_s);
  std::string text = line;
  if (!note_.empty()) text += "  " + note_;
  const size_t length = text.size() - 1;  // after the '\r'
  if (length < drawn_length_) text.append(drawn_length_ - length, ' ');
  drawn_length_ = length;
  *out_ << text << std::flush;
}

}  // namespace vio::tools
