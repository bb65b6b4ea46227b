#pragma once
// Ground truth of a front end's matches on a dataset `vio simulate` made
// (`vio matchcheck`). Each observation's rectified left pixel is cast as a ray
// from the true camera (the ground truth interpolated at its timestamp, as
// the renderer placed it) into the scene (mav0/scene.csv): the surface point
// it sees. A landmark id's first observation fixes the point the id stands
// for (its anchor). A later observation of the id is correct when the point
// it sees is within max_error_px of its anchor, measured in the footprint of
// a pixel there (depth / f / cos(incidence), of whichever of the two views is
// coarser, so that grazing views of a floor are not called wrong for their
// pixel noise), or when its anchor, seen from that frame's true camera, is in
// front, projects within max_error_px of the pixel and nothing hides it (at
// an edge the pixel's ray may pass the anchor and meet a surface behind).
//
// Frames are those of observations.csv, in order; a later observation is
//   continuing  when the id was observed in the previous frame,
//   reacquired  when it was observed before, but not in the previous frame
//               (a front end's re-identification, or a track resumed after
//               a frame without it).
// A new id that sees the anchor of an id not observed in the previous frame
// (nor in this one) is a missed return: a point seen before, given a new id.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "vio/dataset/euroc_dataset.h"
#include "vio/estimator/types.h"
#include "vio/simulator/scene.h"

namespace vio::tools {

struct MatchTruthOptions {
  /// Largest distance, in pixel footprints, between the point an observation
  /// sees and its landmark's anchor for a correct observation [px].
  double max_error_px = 3.0;
};

struct MatchCounts {
  std::int64_t correct = 0;
  std::int64_t wrong = 0;
  std::int64_t total() const { return correct + wrong; }
};

struct MatchTruth {
  std::int64_t frames = 0;
  std::int64_t observations = 0;
  /// No ground truth at the frame's time, or the ray leaves the scene (an unchecked
  /// first observation gives the id no anchor; its later ones count as new).
  std::int64_t unchecked = 0;
  std::int64_t new_ids = 0;  ///< first observations of an id (anchors)
  MatchCounts continuing;
  MatchCounts reacquired;
  std::int64_t missed_returns = 0;  ///< new ids on the anchor of an id not observed in the previous frame

  /// reacquired.correct / (reacquired.correct + missed_returns); 0 when both are 0.
  double ReacquisitionRate() const;
  /// reacquired.wrong / reacquired.total(); 0 when none was reacquired.
  double FalseReacquisitionRate() const;
};

/// Checks `frames` (sorted by time, as ReadObservationsCsv gives them) taken
/// by the stereo camera `stereo` along `groundtruth` (body in world, sorted)
/// in `scene`. Throws std::invalid_argument when max_error_px is not > 0.
MatchTruth CheckMatches(const Scene& scene, const RectifiedStereo& stereo,
                        const std::vector<GroundTruthState>& groundtruth, const std::vector<StereoFrame>& frames,
                        const MatchTruthOptions& options);

/// One JSON object with every count and both rates.
std::string MatchTruthJson(const MatchTruth& truth);

}  // namespace vio::tools
