#pragma once
// observations.csv: the stereo observations a run gave its estimator, one row
// per observation, rows in frame order:
//   #timestamp [ns],landmark_id,u_L [px],u_R [px],v [px]
// with (u_L, u_R, v) the rectified measurement (stereo_geometry.h) exactly as
// the estimator consumed it (shortest round-trip doubles). `vio run
// --output_observations` writes it; `vio matchcheck` reads it.
#include <fstream>
#include <string>
#include <vector>

#include "vio/estimator/types.h"

namespace vio::tools {

/// Appends frames to observations.csv as they are made (a whole sequence is
/// never held in memory).
class ObservationsCsvWriter {
 public:
  /// Creates `path` with its header; throws DatasetError "<path>: cannot write".
  explicit ObservationsCsvWriter(std::string path);
  /// One frame's rows; throws DatasetError when the file cannot be written
  /// or a measurement is not finite.
  void Add(const StereoFrame& frame);
  /// Flushes; throws DatasetError when the file could not be written whole.
  void Close();

 private:
  std::string path_;
  std::ofstream out_;
};

/// The frames of an observations.csv (rows of one timestamp grouped, frames in
/// file order). Throws DatasetError "<path>:<line>: ..." on a malformed row,
/// a timestamp going backwards or an id given twice in one frame.
std::vector<StereoFrame> ReadObservationsCsv(const std::string& path);

}  // namespace vio::tools
