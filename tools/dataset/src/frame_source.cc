#include "vio/dataset/frame_source.h"

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

// The `features` front end: features0/data.csv rectified up front.
class FeaturesSource final : public FrameSource {
 public:
  FeaturesSource(const EurocDataset& dataset, const frontend::StereoRectifier& rectifier, double max_epipolar_px)
      : frames_(StereoFramesFromFeatures(dataset.features, dataset.frames[0], rectifier, max_epipolar_px,
                                         &report_)) {}

  size_t size() const override { return frames_.size(); }
  Timestamp time(size_t k) const override { return frames_[k].t_ns; }
  StereoFrame Frame(size_t k, const Estimator&) override { return frames_[k]; }

  std::string ReportJson() const override {
    const StereoFramesReport& r = report_;
    std::ostringstream os;
    os << "{\"source\": \"features\", \"frames\": " << r.frames << ", \"stereo_observations\": "
       << r.stereo_observations << ", \"left_only\": " << r.left_only << ", \"right_only\": " << r.right_only
       << ", \"rejected_epipolar\": " << r.rejected_epipolar << ", \"rejected_disparity\": " << r.rejected_disparity
       << ", \"rejected_outside_image\": " << r.rejected_outside_image << ", \"unrectifiable\": " << r.unrectifiable << ", \"observations_off_frames\": "
       << r.observations_off_frames << "}";
    return os.str();
  }

 private:
  StereoFramesReport report_;
  std::vector<StereoFrame> frames_;
};

}  // namespace

std::string ResolveFrontend(const std::string& frontend, const EurocDataset& dataset) {
  if (frontend != "auto") return frontend;
  if (!dataset.features.empty()) return "features";
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
  if (dataset.features.empty()) {
    const std::string images_hint =
        HasImageFiles(dataset.root) ? "; it has images: run an image front end with --frontend=brisk or --frontend=klt" : "";
    throw std::runtime_error(dataset.root + ": no mav0/features0/data.csv: the 'features' front end needs it "
                             "(generate one with `vio simulate --from=" + dataset.root + "`)" + images_hint);
  }
  return std::make_unique<FeaturesSource>(dataset, rectifier, options.max_epipolar_px);
}

}  // namespace vio::tools
