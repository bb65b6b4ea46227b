#pragma once
// Simulated feature tracks: what an ideal stereo tracker would report from
// the scene's landmarks.
//
// Per frame, a landmark is visible in a camera when it is in front, within
// [min_range, max_range], on a surface facing the camera, not behind a box
// (segment test against every other box), and inside the image under the
// real distortion (with a border). Selection mimics a tracker with a feature
// budget: the landmarks tracked in the previous frame that are still visible
// in cam0 are kept first; the remaining budget goes to new landmarks spread
// over a grid of image cells (least occupied cell first; inside a cell,
// landmarks also visible in cam1 first, then by a fixed random "corner
// strength"). Every selected landmark yields a cam0 observation and, when
// visible there, a cam1 observation; pixels get Gaussian noise and, with
// probability outlier_rate, are replaced by a uniform random pixel.
#include <array>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "vio/estimator/types.h"
#include "vio/dataset/euroc_dataset.h"
#include "vio/simulator/scene.h"

namespace vio::tools {

struct FeatureSimOptions {
  /// Nearest observable landmark [m].
  double min_range_m = 0.25;
  /// Farthest observable landmark [m].
  double max_range_m = 20.0;
  /// Standard deviation of the pixel noise, per coordinate [px].
  double pixel_noise_px = 0.5;
  /// Probability that an observation is replaced by a random pixel [0, 1].
  double outlier_rate = 0.0;
  /// Feature budget per frame (cam0 tracks).
  int max_features = 150;
  /// Columns of the grid of image cells new features are spread over.
  int grid_cols = 8;
  /// Rows of that grid.
  int grid_rows = 6;
  /// Observations keep this distance to the image border [px].
  double border_px = 2.0;
};

/// The body pose at one camera frame.
struct FramePose {
  Timestamp t_ns = 0;
  Eigen::Isometry3d T_w_b = Eigen::Isometry3d::Identity();
};

struct FeatureSimulation {
  /// Sorted by (t, camera, feature_id); feature_id = landmark index.
  std::vector<FeatureObservation> observations;
  std::vector<int> cam0_count;    ///< observations in cam0, per frame
  std::vector<int> stereo_count;  ///< landmarks observed in both cameras, per frame
  std::vector<int> track_lengths; ///< frames of every maximal run of a landmark in cam0
};

/// Throws std::invalid_argument on bad options (ranges, budget, rates).
FeatureSimulation SimulateFeatures(const Scene& scene, const std::array<CameraCalibration, 2>& cameras,
                                   const std::vector<FramePose>& frames, const FeatureSimOptions& options,
                                   std::mt19937_64* rng);

/// Median of the track lengths (0 when there are none).
double MedianTrackLength(const FeatureSimulation& features);

}  // namespace vio::tools
