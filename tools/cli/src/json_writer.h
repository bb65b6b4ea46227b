#pragma once
// The tiny JSON writer of the CLI's output files (summary.json, vio verify
// --json): escaped strings and numbers; objects are written by the callers.
#include <string>

namespace vio::tools {

/// A JSON string literal: quotes, backslashes and control characters escaped.
std::string JsonString(const std::string& s);
/// A JSON number with 8 significant digits; null when not finite.
std::string JsonNumber(double value);

}  // namespace vio::tools
