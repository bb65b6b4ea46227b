#pragma once
// Where a run's stereo observations come from: the front end as seen by
// `vio run`. One implementation per front end; the estimator never knows
// which one ran.
#include <memory>
#include <string>

#include "vio/estimator/estimator.h"
#include "vio/frontend/stereo_rectifier.h"
#include "vio/dataset/euroc_dataset.h"
#include "vio/frontend/frontend_options.h"

namespace vio::tools {

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  /// Number of frames (cam0 stamps).
  virtual size_t size() const = 0;
  /// Stamp of frame k.
  virtual Timestamp time(size_t k) const = 0;
  /// The observations of frame k. Called once per frame in order, after the
  /// IMU up to the frame was given to `estimator` (which can predict the body
  /// pose at the frame and knows the current landmark estimates).
  virtual StereoFrame Frame(size_t k, const Estimator& estimator) = 0;
  /// Counts for summary.json's "frontend" object (a JSON object).
  virtual std::string ReportJson() const = 0;
  /// Set when the frames show the input cannot be right (swapped cameras): what is wrong and how to
  /// fix it. The run stops there.
  virtual std::string InputProblem() const { return ""; }
};

/// The front end `frontend` (a FrontendOptions::frontend value) stands for on
/// `dataset`: `auto` is `features` when the dataset has features0, else `klt`
/// when it has images (logged in one line), else an error; any other value is
/// itself. Throws std::runtime_error when `auto` finds nothing to track.
std::string ResolveFrontend(const std::string& frontend, const EurocDataset& dataset);

/// The source `options.frontend` names (resolved: not `auto`). Throws
/// std::runtime_error when the dataset lacks what it needs.
std::unique_ptr<FrameSource> MakeFrameSource(const FrontendOptions& options, const EurocDataset& dataset,
                                             const frontend::StereoRectifier& rectifier);

/// `source` with every frame stamp moved by `shift_ns` onto the IMU's clock (a camera-IMU time
/// offset: EurocDataset::camera_time_offset_ns, shift = -camera_time_offset_ns); `source` itself when 0.
std::unique_ptr<FrameSource> ShiftFrameTimes(std::unique_ptr<FrameSource> source, Timestamp shift_ns);

}  // namespace vio::tools
