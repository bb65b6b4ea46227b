#include "vio/dataset/frame_source.h"

#include <algorithm>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include <glog/logging.h>

#include "frame_source_images.h"
#include "vio/dataset/stereo_frames.h"

namespace vio::tools {
namespace {

// True when mav0/cam0/data/ holds any file.
bool HasImageFiles(const std::string& root) {
  std::error_code ec;
  const std::filesystem::path folder = std::filesystem::path(root) / "mav0" / "cam0" / "data";
  return std::filesystem::is_directory(folder, ec) &&
         std::filesystem::directory_iterator(folder, ec) != std::filesystem::directory_iterator();
}

// The counts of summary.json's "frontend" object for the features source.
std::string FeaturesReportJson(const StereoFramesReport& r) {
  std::ostringstream os;
  os << "{\"source\": \"features\", \"frames\": " << r.frames << ", \"stereo_observations\": "
     << r.stereo_observations << ", \"left_only\": " << r.left_only << ", \"right_only\": " << r.right_only
     << ", \"rejected_epipolar\": " << r.rejected_epipolar << ", \"rejected_disparity\": " << r.rejected_disparity
     << ", \"rejected_outside_image\": " << r.rejected_outside_image << ", \"unrectifiable\": " << r.unrectifiable
     << ", \"observations_off_frames\": " << r.observations_off_frames
     << ", \"consistent_if_swapped\": " << r.consistent_if_swapped << "}";
  return os.str();
}

// The `features` front end on features held in memory: rectified up front.
class FeaturesSource final : public FrameSource {
 public:
  FeaturesSource(const EurocDataset& dataset, const frontend::StereoRectifier& rectifier, double max_epipolar_px)
      : frames_(StereoFramesFromFeatures(dataset.features, dataset.frames[0], rectifier, max_epipolar_px,
                                         &report_)) {}

  size_t size() const override { return frames_.size(); }
  Timestamp time(size_t k) const override { return frames_[k].t_ns; }
  StereoFrame Frame(size_t k, const Estimator&) override { return frames_[k]; }
  std::string ReportJson() const override { return FeaturesReportJson(report_); }
  std::string InputProblem() const override { return SwappedCamerasProblem(report_); }

 private:
  StereoFramesReport report_;
  std::vector<StereoFrame> frames_;
};

// The `features` front end streaming features0/data.csv: each frame's rows are
// read and rectified when the frame is asked for (inside the run's timing).
// Rows of stamps that are no cam0 frame are counted as off frames; rows of
// frames the run skipped, and after the last frame asked for, are not read.
class FeatureStreamSource final : public FrameSource {
 public:
  FeatureStreamSource(const EurocDataset& dataset, const frontend::StereoRectifier& rectifier,
                      double max_epipolar_px)
      : stream_(dataset.features_file), rectifier_(rectifier), max_epipolar_px_(max_epipolar_px) {
    for (const CameraFrame& frame : dataset.frames[0]) times_.push_back(frame.t_ns);
    report_.frames = static_cast<int>(times_.size());
  }

  size_t size() const override { return times_.size(); }
  Timestamp time(size_t k) const override { return times_[k]; }

  StereoFrame Frame(size_t k, const Estimator&) override {
    const Timestamp t_ns = times_[k];
    while (pending_ || (pending_ = stream_.Next(&group_))) {
      const Timestamp group_t_ns = group_.front().t_ns;
      if (group_t_ns > t_ns) break;
      pending_ = false;
      if (group_t_ns == t_ns) return StereoFrameFromFeatures(t_ns, group_, rectifier_, max_epipolar_px_, &report_);
      if (!std::binary_search(times_.begin(), times_.end(), group_t_ns)) {
        report_.observations_off_frames += static_cast<int>(group_.size());
      }
    }
    StereoFrame empty;
    empty.t_ns = t_ns;
    return empty;
  }

  std::string ReportJson() const override { return FeaturesReportJson(report_); }
  std::string InputProblem() const override { return SwappedCamerasProblem(report_); }

 private:
  FeatureCsvStream stream_;
  const frontend::StereoRectifier& rectifier_;
  const double max_epipolar_px_;
  std::vector<Timestamp> times_;
  std::vector<FeatureObservation> group_;
  bool pending_ = false;  ///< group_ read and not yet used
  StereoFramesReport report_;
};

// Another source's frames with their stamps moved onto the IMU's clock.
class ShiftedSource final : public FrameSource {
 public:
  ShiftedSource(std::unique_ptr<FrameSource> source, Timestamp shift_ns)
      : source_(std::move(source)), shift_ns_(shift_ns) {}

  size_t size() const override { return source_->size(); }
  Timestamp time(size_t k) const override { return source_->time(k) + shift_ns_; }
  StereoFrame Frame(size_t k, const Estimator& estimator) override {
    StereoFrame frame = source_->Frame(k, estimator);
    frame.t_ns += shift_ns_;
    return frame;
  }
  std::string ReportJson() const override { return source_->ReportJson(); }
  std::string InputProblem() const override { return source_->InputProblem(); }

 private:
  std::unique_ptr<FrameSource> source_;
  Timestamp shift_ns_;
};

}  // namespace

std::string ResolveFrontend(const std::string& frontend, const EurocDataset& dataset) {
  if (frontend != "auto") return frontend;
  if (!dataset.features.empty() || !dataset.features_file.empty()) return "features";
  if (dataset.has_images) {
    LOG(INFO) << dataset.root << ": no mav0/features0/data.csv, running the klt front end on the images "
              << "(--frontend=features|brisk|klt overrides)";
    return "klt";
  }
  throw std::runtime_error(dataset.root + ": neither mav0/features0/data.csv nor images in mav0/cam0/data/: "
                           "nothing to track (generate features with `vio simulate --from=" + dataset.root + "`)");
}

std::unique_ptr<FrameSource> MakeFrameSource(const FrontendOptions& options, const EurocDataset& dataset,
                                             const frontend::StereoRectifier& rectifier) {
  if (options.frontend != "features") return MakeImageFrameSource(options, dataset, rectifier);
  if (!dataset.features_file.empty()) {
    return std::make_unique<FeatureStreamSource>(dataset, rectifier, options.max_epipolar_px);
  }
  if (dataset.features.empty()) {
    const std::string images_hint =
        HasImageFiles(dataset.root) ? "; it has images: run an image front end with --frontend=brisk or --frontend=klt" : "";
    throw std::runtime_error(dataset.root + ": no mav0/features0/data.csv: the 'features' front end needs it "
                             "(generate one with `vio simulate --from=" + dataset.root + "`)" + images_hint);
  }
  return std::make_unique<FeaturesSource>(dataset, rectifier, options.max_epipolar_px);
}

std::unique_ptr<FrameSource> ShiftFrameTimes(std::unique_ptr<FrameSource> source, Timestamp shift_ns) {
  if (shift_ns == 0) return source;
  return std::make_unique<ShiftedSource>(std::move(source), shift_ns);
}

}  // namespace vio::tools
