#pragma once
// The valid values of a numeric option. An Options struct declares it next
// to the field in its `Visit` (v("window_size", window_size, "doc", AtLeast(1)));
// the option registry checks it wherever the option is set (YAML file, flag)
// and shows it in --help.
#include <limits>

namespace vio {

struct OptionRange {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_exclusive = false;  ///< (min, max] instead of [min, max]
};

/// [min, inf)
inline OptionRange AtLeast(double min) { return {min, std::numeric_limits<double>::infinity(), false}; }
/// (0, max]
inline OptionRange Positive(double max = std::numeric_limits<double>::infinity()) { return {0.0, max, true}; }
/// [min, max]
inline OptionRange Between(double min, double max) { return {min, max, false}; }

}  // namespace vio
