#pragma once
// Statistics of a stereo image sequence, to compare rendered frames with real
// ones (`vio imagestats`): per image grey level, contrast, gradient energy and
// corner counts; per sequence what the KLT front end makes of it.
#include <string>
#include <vector>

#include "vio/frontend/frontend_options.h"

namespace vio::tools {

struct ImageStatisticsOptions {
  /// Stereo pairs read at most, from the first one [count].
  int max_frames = 200;
  /// FAST threshold of the corner count (with non-maximum suppression) [grey levels].
  int fast_threshold = 20;
  /// BRISK detection threshold of the corner count [grey levels].
  int brisk_threshold = 30;
  /// Front-end options of the KLT run (its `frontend` is set to klt).
  FrontendOptions frontend;
};

/// Means over the left images (grey statistics, corners) and the KLT run.
struct ImageStatistics {
  std::string name;             ///< the dataset folder's name
  int frames = 0;               ///< stereo pairs read
  double mean_grey = 0.0;       ///< [grey levels]
  double contrast = 0.0;        ///< standard deviation of the grey levels [grey levels]
  double gradient_energy = 0.0; ///< mean squared central-difference gradient [grey^2 / px^2]
  double fast_corners = 0.0;    ///< FAST corners per image
  double brisk_corners = 0.0;   ///< BRISK keypoints per image
  double klt_features = 0.0;    ///< KLT stereo features per frame
  double klt_track_length = 0.0;///< median KLT track length [frames observed] (at most `frames`)
  double klt_row_difference_px = 0.0;  ///< median |v_L - v_R| of KLT stereo matches [px]
};

/// Reads the stereo pairs of the ASL folder `dataset_dir` (cam0/cam1 rows
/// paired by stamp) and measures them. Throws DatasetError when the folder
/// cannot be read or has no stereo pair.
ImageStatistics MeasureImageStatistics(const std::string& dataset_dir, const ImageStatisticsOptions& options);

/// A Markdown table, one row per sequence.
std::string StatisticsTable(const std::vector<ImageStatistics>& rows);

}  // namespace vio::tools
