#pragma once
// Options of the front end: where the per-frame stereo observations come from
// and the parameters of the two image front ends (paper §5.2 BRISK, KLT).
#include <string>

#include "vio/estimator/option_range.h"

namespace vio {

struct FrontendOptions {
  /// auto: features0 when the dataset has it, else klt on the images;
  /// features: the dataset's features0/data.csv; brisk / klt: the images.
  std::string frontend = "auto";
  /// Stereo pairs whose rectified rows differ by more are rejected [px].
  double max_epipolar_px = 2.0;
  /// Side of the square cells that spread features over the image [px].
  double grid_cell_px = 48.0;
  /// Temporal matches whose reprojection into the IMU-predicted camera is
  /// further than this from the measurement are rejected [px].
  double max_reprojection_px = 8.0;
  /// BRISK: AGAST detection threshold [grey levels].
  int brisk_threshold = 20;
  /// BRISK: scale-space octaves.
  int brisk_octaves = 0;
  /// BRISK: strongest keypoints kept per grid cell and image [count].
  int brisk_per_cell = 5;
  /// BRISK: largest disparity of a stereo match, the right keypoints further left are no candidates [px].
  double brisk_max_disparity_px = 128.0;
  /// BRISK: largest Hamming distance of an accepted descriptor match [bits of 512].
  int max_hamming_bits = 90;
  /// BRISK: tracks seen in the last this many frames are matched to the new one [frames].
  int track_window_frames = 3;
  /// BRISK and KLT: landmarks the estimator holds (FramePrior::landmarks) but
  /// the front end lost are sought again within this distance of their
  /// projection into the IMU-predicted camera: BRISK by their descriptors, in
  /// u_L, u_R and v; KLT by a remembered left-image patch and ZNCC, in the raw
  /// left image [px]; 0 = off.
  double reidentify_radius_px = 0.0;
  /// KLT: most features per grid cell; new corners fill cells below it [count].
  int klt_per_cell = 4;
  /// KLT: most features in the image [count].
  int klt_max_features = 300;
  /// KLT: FAST corner threshold [grey levels].
  int klt_fast_threshold = 20;
  /// KLT: minimum distance between features [px].
  double klt_min_distance_px = 10.0;
  /// KLT: Lucas-Kanade window side [px].
  int klt_window_px = 15;
  /// KLT: pyramid levels above the full image.
  int klt_pyramid_levels = 3;
  /// KLT: largest forward-backward tracking error [px].
  double klt_max_fb_px = 1.0;
  /// KLT: largest disparity the stereo row search tries [px].
  double klt_max_disparity_px = 128.0;
  /// KLT: smallest ZNCC score of a stereo row-search match [-1, 1].
  double klt_min_ncc = 0.8;
  /// Folder receiving one PNG per frame with the tracks drawn; empty = none.
  std::string debug_images;
  /// Image runs: threads of the pipeline; 1: everything on one thread; 2:
  /// reading, decoding and the pyramids on a second one; 0: 2 when the
  /// process may use two processors, else 1. Results do not depend on it.
  int pipeline_threads = 0;

  template <class V>
  void Visit(V& v) {
    v("frontend", frontend,
      "source of stereo observations: auto = features0 when the dataset has it, else klt on the images; "
      "features = the dataset's features0/data.csv, brisk = BRISK matching on the images (paper 5.2), "
      "klt = Lucas-Kanade tracking on the images",
      {"auto", "features", "brisk", "klt"});
    v("max_epipolar_px", max_epipolar_px, "reject stereo pairs whose rectified rows differ by more [px]", Positive());
    v("grid_cell_px", grid_cell_px, "side of the grid cells spreading image features [px]", AtLeast(1));
    v("max_reprojection_px", max_reprojection_px,
      "reject temporal matches further from their IMU-predicted reprojection [px]", Positive());
    v("brisk_threshold", brisk_threshold, "BRISK AGAST detection threshold [grey levels]", Between(0, 255));
    v("brisk_octaves", brisk_octaves, "BRISK scale-space octaves [count]", Between(0, 8));
    v("brisk_per_cell", brisk_per_cell, "BRISK keypoints kept per grid cell and image [count]", AtLeast(1));
    v("brisk_max_disparity_px", brisk_max_disparity_px, "BRISK largest disparity of a stereo match [px]", Positive());
    v("max_hamming_bits", max_hamming_bits, "largest Hamming distance of a BRISK match [bits of 512]", Between(0, 512));
    v("track_window_frames", track_window_frames,
      "BRISK matches the new frame to tracks seen in this many previous frames [frames]", AtLeast(1));
    v("reidentify_radius_px", reidentify_radius_px,
      "BRISK (by descriptors) and KLT (by a remembered patch and ZNCC) re-identify lost landmarks the estimator "
      "holds within this distance of their IMU-predicted projection (use with persistent_landmarks); 0 = off [px]",
      AtLeast(0));
    v("klt_per_cell", klt_per_cell, "KLT most features per grid cell [count]", AtLeast(1));
    v("klt_max_features", klt_max_features, "KLT most features in the image [count]", AtLeast(1));
    v("klt_fast_threshold", klt_fast_threshold, "KLT FAST corner threshold [grey levels]", Between(0, 255));
    v("klt_min_distance_px", klt_min_distance_px, "KLT minimum distance between features [px]", AtLeast(0));
    v("klt_window_px", klt_window_px, "KLT Lucas-Kanade window side [px]", AtLeast(3));
    v("klt_pyramid_levels", klt_pyramid_levels, "KLT pyramid levels above the full image [count]", Between(0, 8));
    v("klt_max_fb_px", klt_max_fb_px, "KLT largest forward-backward tracking error [px]", Positive());
    v("klt_max_disparity_px", klt_max_disparity_px, "KLT largest disparity the stereo row search tries [px]", Positive());
    v("klt_min_ncc", klt_min_ncc, "KLT smallest ZNCC score of a stereo row-search match [-1, 1]", Between(-1, 1));
    v("debug_images", debug_images, "folder for one PNG per frame with the tracks drawn; empty = none");
    v("pipeline_threads", pipeline_threads,
      "image front ends: threads of the pipeline; 1 = all on one thread, 2 = image reading, decoding and "
      "pyramids on a second thread, 0 = 2 when the process may use two processors, else 1; the results are "
      "the same for every value [count]",
      Between(0, 2));
  }
};

}  // namespace vio
