#pragma once
// The `features` front end: a dataset's features0 observations (distorted
// pixels of cam0 and cam1) turned into the estimator's StereoFrames of
// rectified (u_L, u_R, v) measurements.
#include <string>
#include <vector>

#include "vio/frontend/stereo_rectifier.h"
#include "vio/dataset/euroc_dataset.h"

namespace vio::tools {

/// What happened to the observations (nothing is dropped without a count).
struct StereoFramesReport {
  int frames = 0;                  ///< frames produced (one per cam0 stamp)
  int stereo_observations = 0;     ///< landmarks seen in both cameras, kept
  int left_only = 0;               ///< seen in cam0 only (not used by the stereo model)
  int right_only = 0;              ///< seen in cam1 only (not used)
  int rejected_epipolar = 0;       ///< rectified rows differ by more than the bound
  int rejected_disparity = 0;      ///< disparity <= 0 (behind or at infinity)
  int rejected_outside_image = 0;  ///< a pixel outside its image (calibration resolution)
  int unrectifiable = 0;           ///< a pixel that cannot be undistorted
  int observations_off_frames = 0; ///< feature rows whose stamp is no cam0 frame
  /// Pairs rejected (epipolar or disparity) that pass both with the cameras exchanged (cam0's
  /// point as cam1's and back): evidence of swapped cameras.
  int consistent_if_swapped = 0;
};

/// The StereoFrame of stamp t_ns from that stamp's features (both cameras);
/// adds to `report`'s observation counts.
StereoFrame StereoFrameFromFeatures(Timestamp t_ns, const std::vector<FeatureObservation>& features,
                                    const frontend::StereoRectifier& rectifier, double max_epipolar_px,
                                    StereoFramesReport* report);

/// One StereoFrame per cam0 frame stamp (empty frames included), observations
/// sorted by landmark id.
std::vector<StereoFrame> StereoFramesFromFeatures(const std::vector<FeatureObservation>& features,
                                                  const std::vector<CameraFrame>& cam0_frames,
                                                  const frontend::StereoRectifier& rectifier,
                                                  double max_epipolar_px, StereoFramesReport* report);

/// Swapped cameras: when at least kSwappedMinPairs stereo pairs were seen and most of them fit the
/// stereo geometry only with the cameras exchanged (consistent_if_swapped), what is wrong and how to
/// fix it; empty otherwise.
inline constexpr int kSwappedMinPairs = 100;
std::string SwappedCamerasProblem(const StereoFramesReport& report);

}  // namespace vio::tools
