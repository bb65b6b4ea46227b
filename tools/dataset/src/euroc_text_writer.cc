#include <glog/logging.h>

#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "text_writer.h"
#include "vio/dataset/euroc_dataset.h"

namespace vio::tools {

TextWriter& TextWriter::Int(std::int64_t value) {
  std::array<char, 24> buffer;
  const auto [end, ec] = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  CHECK(ec == std::errc());
  text_.append(buffer.data(), end);
  return *this;
}

TextWriter& TextWriter::Double(double value) {
  if (!std::isfinite(value)) {
    throw DatasetError(path_ + ": refusing to write a non-finite value (" + std::to_string(value) +
                       "); readers reject NaN and inf");
  }
  std::array<char, 32> buffer;
  const auto [end, ec] = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  CHECK(ec == std::errc());
  text_.append(buffer.data(), end);
  return *this;
}

TextWriter& TextWriter::Real(double value) {
  const std::size_t start = text_.size();
  Double(value);
  if (text_.find_first_of(".e", start) == std::string::npos) text_ += ".0";
  return *this;
}

TextWriter& TextWriter::DecimalSeconds(std::int64_t t_ns) {
  constexpr std::uint64_t kNanosPerSecond = 1'000'000'000;
  const bool negative = t_ns < 0;
  const std::uint64_t magnitude =
      negative ? ~static_cast<std::uint64_t>(t_ns) + 1 : static_cast<std::uint64_t>(t_ns);
  std::array<char, 32> buffer;
  const int n = std::snprintf(buffer.data(), buffer.size(), "%s%llu.%09llu", negative ? "-" : "",
                              static_cast<unsigned long long>(magnitude / kNanosPerSecond),
                              static_cast<unsigned long long>(magnitude % kNanosPerSecond));
  CHECK_GT(n, 0);
  text_.append(buffer.data(), n);
  return *this;
}

TextWriter& TextWriter::Text(std::string_view text) {
  text_.append(text);
  return *this;
}

TextWriter& TextWriter::Header(const std::vector<std::string>& columns) {
  text_ += '#';
  for (std::size_t i = 0; i < columns.size(); ++i) {
    if (i > 0) text_ += ',';
    text_ += columns[i];
  }
  text_ += '\n';
  return *this;
}

void TextWriter::Save() const {
  const std::filesystem::path parent = std::filesystem::path(path_).parent_path();
  std::error_code ec;
  if (!parent.empty()) std::filesystem::create_directories(parent, ec);
  if (ec)
    throw DatasetError(path_ + ": cannot create folder " + parent.string() + ": " + ec.message());
  std::ofstream out(path_, std::ios::binary | std::ios::trunc);
  out.write(text_.data(), static_cast<std::streamsize>(text_.size()));
  out.close();
  if (!out) throw DatasetError(path_ + ": cannot write");
}

}  // namespace vio::tools
