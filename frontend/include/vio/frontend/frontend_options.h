#pragma once
// Options of the front end: where the per-frame stereo observations come from.
#include <string>

namespace vio {

struct FrontendOptions {
  /// features: the dataset's features0/data.csv (simulated or external tracker).
  std::string frontend = "features";
  /// Stereo pairs whose rectified rows differ by more are rejected [px].
  double max_epipolar_px = 2.0;

  template <class V>
  void Visit(V& v) {
    v("frontend", frontend, "source of stereo observations: the dataset's features0/data.csv",
      {"features"});
    v("max_epipolar_px", max_epipolar_px, "reject stereo pairs whose rectified rows differ by more [px]");
  }
};

}  // namespace vio
