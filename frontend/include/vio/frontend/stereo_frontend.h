#pragma once
// A stereo front end on images: one stereo pair in, the frame's stereo
// observations out (vio::StereoFrame, rectified (u_L, u_R, v) per landmark),
// so the estimator never knows which front end ran.
//
// Process() runs the steps every image front end shares around the
// implementation's own detection and matching (TrackFrame):
//   1. TrackFrame: detect, match left-right (epipolar check on rectified
//      rows), match over time; the implementation calls RejectOutliers on its
//      temporal matches: the landmark (the window's estimate, else the track's
//      own stereo triangulation) is projected into the IMU-predicted camera
//      and the match is dropped when it lands more than max_reprojection_px
//      from the measurement in u_L, u_R or v;
//   2. the stereo features become the frame's observations, the two-way
//      index (FeatureTracks) records them and each track's triangulation is
//      stored in the world (when the pose is predicted);
//   3. statistics and stage times are accumulated.
#include <array>
#include <map>
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "vio/estimator/types.h"
#include "vio/estimator/window.h"
#include "vio/frontend/feature_tracks.h"
#include "vio/frontend/frontend_options.h"
#include "vio/frontend/stereo_rectifier.h"

namespace vio::frontend {

/// What the estimator knows about the frame being processed.
struct FramePrior {
  /// IMU-predicted body pose at the frame; nullopt before initialization.
  std::optional<Eigen::Isometry3d> T_w_b;
  /// Current landmark estimates of the window (may be null).
  const std::map<LandmarkId, Landmark>* landmarks = nullptr;
};

/// One feature of a frame as a front end sees it.
struct FrameFeature {
  LandmarkId id;
  Eigen::Vector2d uv0_px = Eigen::Vector2d::Zero();  ///< left image, distorted [px]
  Eigen::Vector2d uv1_px = Eigen::Vector2d::Zero();  ///< right image, distorted [px] (when stereo)
  Eigen::Vector3d z_px = Eigen::Vector3d::Zero();    ///< rectified (u_L, u_R, v) [px] (when stereo)
  bool stereo = false;   ///< matched left-right: an observation of the frame
  bool tracked = false;  ///< continues a track of an earlier frame
};

/// A stereo pair and what a front end derives from the images alone (no
/// estimator state): filled by StereoFrontend::Prepare, which may run on
/// another thread than Process. Reused from pair to pair, so its buffers are
/// allocated once.
struct PreparedPair {
  cv::Mat left, right;  ///< CV_8UC1, the calibrated size
  /// KLT: the LK pyramids (with derivatives) of the left image over
  /// klt_pyramid_levels and of the right image at full resolution.
  std::vector<cv::Mat> left_pyramid, right_pyramid;
  /// KLT: the FAST corners of the whole left image (nonmax-suppressed), when
  /// Prepare was asked for them (corners_ready); else the tracker finds them
  /// only in the grid cells that need new features.
  std::vector<cv::KeyPoint> corners;
  bool corners_ready = false;
};

/// Wall time of the front-end stages [ms].
struct StageTimes {
  double detect_ms = 0;
  double stereo_ms = 0;
  double temporal_ms = 0;
  double reject_ms = 0;
  double prepare_ms = 0;  ///< Prepare (KLT: the pyramids), wherever it ran
  double total() const { return detect_ms + stereo_ms + temporal_ms + reject_ms + prepare_ms; }
};

/// Counts over all processed frames.
struct FrontendStats {
  std::int64_t frames = 0;
  std::vector<int> observations_per_frame;  ///< stereo observations emitted per frame
  std::int64_t stereo_candidates = 0;       ///< left-right matches before the epipolar check
  std::int64_t stereo_inliers = 0;          ///< of which passed the epipolar and disparity checks
  std::int64_t temporal_matches = 0;        ///< matches to earlier tracks before the reprojection check
  std::int64_t rejected_reprojection = 0;   ///< of which rejected against the predicted pose
  std::int64_t new_tracks = 0;              ///< tracks started
  std::int64_t reidentified = 0;            ///< features given back the id of a landmark no recent frame matched
  std::int64_t row_searches = 0;            ///< KLT: stereo row searches (new corners, retried tracks)
  StageTimes time;                          ///< summed over frames [ms]
  /// |v_L - v_R| of the stereo inliers in 0.01 px bins.
  std::vector<std::int64_t> row_difference_histogram;

  /// Median |v_L - v_R| of the stereo inliers [px] (0 when none).
  double MedianRowDifferencePx() const;
};

class StereoFrontend {
 public:
  /// Throws std::invalid_argument naming a non-positive or inconsistent option.
  StereoFrontend(const FrontendOptions& options, const StereoRectifier& rectifier);
  virtual ~StereoFrontend() = default;
  StereoFrontend(const StereoFrontend&) = delete;
  StereoFrontend& operator=(const StereoFrontend&) = delete;

  /// One stereo pair (CV_8UC1, the calibrated size; else std::invalid_argument).
  StereoFrame Process(Timestamp t_ns, const cv::Mat& left, const cv::Mat& right, const FramePrior& prior);
  /// Fills `pair` from a stereo pair (throws like Process for bad images):
  /// the work that needs no estimator state (KLT: the pyramids; with
  /// `with_corners` also the left image's FAST corners). Reads only the
  /// options: safe on another thread while Process runs on an earlier pair.
  void Prepare(const cv::Mat& left, const cv::Mat& right, bool with_corners, PreparedPair* pair) const;
  /// Process on a prepared pair; the same result as on its images. The
  /// front end may swap buffers it keeps (the previous pyramid) into `pair`.
  StereoFrame Process(Timestamp t_ns, PreparedPair* pair, const FramePrior& prior);

  /// The features of the last processed frame.
  const std::vector<FrameFeature>& features() const { return features_; }
  const FeatureTracks& tracks() const { return tracks_; }
  const FrontendStats& stats() const { return stats_; }
  /// Counts the wall time of a Prepare run elsewhere (another thread) for
  /// the last processed frame [ms].
  void AddPrepareTime(double ms);
  /// Stage times of the last frame [ms].
  const StageTimes& last_times() const { return last_times_; }
  const StereoRectifier& rectifier() const { return rectifier_; }
  const FrontendOptions& options() const { return options_; }

 protected:
  /// Detects and matches in one stereo pair; returns the frame's features.
  virtual std::vector<FrameFeature> TrackFrame(PreparedPair* pair, const FramePrior& prior) = 0;
  /// The implementation's share of Prepare (after the images are checked and
  /// stored in `pair`); none by default.
  virtual void PrepareImages(bool /*with_corners*/, PreparedPair* /*pair*/) const {}

  /// The rectified measurement of a left-right pair; nullopt (and not an
  /// inlier) when a pixel cannot be rectified, the rows differ by more than
  /// max_epipolar_px or the disparity is not positive. Counts the candidate.
  std::optional<Eigen::Vector3d> StereoMeasurement(const Eigen::Vector2d& uv0_px, const Eigen::Vector2d& uv1_px);

  /// Removes the tracked stereo features that fail the reprojection check
  /// against the predicted pose (none before initialization); returns the
  /// ids removed.
  std::vector<LandmarkId> RejectOutliers(const FramePrior& prior, std::vector<FrameFeature>* features);

  LandmarkId NewTrack();
  /// Counts features re-identified with a lost landmark (after RejectOutliers).
  void CountReidentified(std::int64_t count) { stats_.reidentified += count; }
  void CountRowSearch() { ++stats_.row_searches; }
  /// The landmark's position: the window's estimate, else the track's own
  /// stereo triangulation; nullopt when neither exists.
  std::optional<Eigen::Vector3d> LandmarkPosition(LandmarkId id, const FramePrior& prior) const;
  /// Adds the elapsed time since `start` to a stage of the current frame.
  void AddTime(double StageTimes::*stage, std::int64_t start_ns);
  static std::int64_t NowNs();

 private:
  StereoFrame Emit(Timestamp t_ns, const FramePrior& prior);

  FrontendOptions options_;
  StereoRectifier rectifier_;
  FeatureTracks tracks_;
  FrontendStats stats_;
  StageTimes last_times_;
  std::vector<FrameFeature> features_;
  PreparedPair scratch_;  ///< Process on plain images prepares into it
};

/// The front end `options.frontend` names ("brisk" or "klt"). Throws std::invalid_argument for another name.
std::unique_ptr<StereoFrontend> MakeStereoFrontend(const FrontendOptions& options,
                                                   const StereoRectifier& rectifier);

}  // namespace vio::frontend
