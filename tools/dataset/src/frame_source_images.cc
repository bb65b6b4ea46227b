#include "frame_source_images.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <future>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <time.h>

#include <glog/logging.h>
#include <opencv2/imgcodecs.hpp>

#include "vio/frontend/stereo_frontend.h"
#include "vio/frontend/track_drawing.h"
#include "vio/dataset/rosbag_dataset.h"

namespace vio::tools {
namespace {

/// Tracks at least this long share the histogram's last bin [frames].
constexpr int kTrackHistogramBins = 30;

double Percentile(std::vector<int> values, double fraction) {
  if (values.empty()) return 0.0;
  const auto k = static_cast<size_t>(fraction * static_cast<double>(values.size() - 1) + 0.5);
  std::nth_element(values.begin(), values.begin() + static_cast<long>(k), values.end());
  return values[k];
}

std::string Number(double x) {
  std::ostringstream os;
  os.precision(6);
  os << x;
  return os.str();
}

// CPU time of the calling thread [ms]: what a stage costs itself, whatever
// else shares the core (wall-clock stage times absorb the other threads).
double ThreadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

class ImageFrameSource final : public FrameSource {
 public:
  ImageFrameSource(const FrontendOptions& options, const EurocDataset& dataset,
                   const frontend::StereoRectifier& rectifier)
      : name_(options.frontend),
        mav0_(dataset.root + "/mav0"),
        debug_dir_(options.debug_images),
        frontend_(frontend::MakeStereoFrontend(options, rectifier)) {
    for (int i = 0; i < 2; ++i) {
      filenames_[i].reserve(dataset.frames[i].size());
      for (const CameraFrame& f : dataset.frames[i]) filenames_[i].push_back(f.filename);
      if (!dataset.image_bag.empty()) bag_readers_[i].emplace(dataset.image_bag, dataset.image_topics[i]);
    }
    PairFrames(dataset);
    if (!debug_dir_.empty()) std::filesystem::create_directories(debug_dir_);
  }

  size_t size() const override { return pairs_.size(); }
  Timestamp time(size_t k) const override { return pairs_[k].t_ns; }

  StereoFrame Frame(size_t k, const Estimator& estimator) override {
    const Pair& pair = pairs_[k];
    const auto start = std::chrono::steady_clock::now();
    const auto [left, right] = TakeImages(k);
    load_ms_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    frontend::FramePrior prior;
    prior.T_w_b = estimator.PredictBodyPose(pair.t_ns);
    prior.landmarks = &estimator.window().landmarks();
    const double cpu_start_ms = ThreadCpuMs();
    StereoFrame frame = frontend_->Process(pair.t_ns, left, right, prior);
    frontend_cpu_ms_ += ThreadCpuMs() - cpu_start_ms;
    if (!debug_dir_.empty()) WriteDebugImage(pair.t_ns, left, right);
    return frame;
  }

  std::string ReportJson() const override;

 private:
  struct Pair {
    Timestamp t_ns;
    size_t left, right;  ///< rows of cam0, cam1 data.csv
  };

  void PairFrames(const EurocDataset& dataset) {
    std::map<Timestamp, size_t> right;
    for (size_t k = 0; k < dataset.frames[1].size(); ++k) right[dataset.frames[1][k].t_ns] = k;
    for (size_t k = 0; k < dataset.frames[0].size(); ++k) {
      const auto it = right.find(dataset.frames[0][k].t_ns);
      if (it == right.end()) {
        ++unpaired_;
        continue;
      }
      pairs_.push_back(Pair{dataset.frames[0][k].t_ns, k, it->second});
    }
    if (unpaired_ > 0) LOG(WARNING) << mav0_ << ": " << unpaired_ << " cam0 frames have no cam1 image; skipped";
  }

  struct LoadedPair {
    cv::Mat left, right;
    double cpu_ms = 0;  ///< CPU time the reading and decoding took on its thread
  };

  // Pair k, decoded by the read-ahead started for it (else now); starts the
  // read-ahead of pair k + 1 on another thread, so decoding overlaps tracking.
  std::pair<cv::Mat, cv::Mat> TakeImages(size_t k) {
    LoadedPair images = next_.valid() && next_k_ == k ? next_.get() : LoadPair(k);
    decode_cpu_ms_ += images.cpu_ms;
    if (k + 1 < pairs_.size()) {
      next_k_ = k + 1;
      next_ = std::async(std::launch::async, [this, k] { return LoadPair(k + 1); });
    }
    return {images.left, images.right};
  }

  LoadedPair LoadPair(size_t k) {
    const double start_ms = ThreadCpuMs();
    LoadedPair images{Load(0, pairs_[k].left), Load(1, pairs_[k].right)};
    images.cpu_ms = ThreadCpuMs() - start_ms;
    return images;
  }

  // The image of one data.csv row: a file under camN/data/, or a bag message.
  cv::Mat Load(int camera, size_t row) {
    if (bag_readers_[camera]) return bag_readers_[camera]->Read(row);
    const std::string path = mav0_ + "/cam" + std::to_string(camera) + "/data/" + filenames_[camera][row];
    cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
    if (image.empty()) throw std::runtime_error(path + ": cannot read the image");
    return image;
  }

  void WriteDebugImage(Timestamp t_ns, const cv::Mat& left, const cv::Mat& right) {
    const std::string path = debug_dir_ + "/" + std::to_string(t_ns) + ".png";
    if (!cv::imwrite(path, drawer_.Draw(left, right, frontend_->features()))) {
      throw std::runtime_error(path + ": cannot write the debug image");
    }
  }

  std::string name_;
  std::string mav0_;
  std::string debug_dir_;
  std::unique_ptr<frontend::StereoFrontend> frontend_;
  frontend::TrackDrawer drawer_;
  std::vector<std::string> filenames_[2];
  std::optional<BagImageReader> bag_readers_[2];  ///< images from a ROS bag: one sequential reader per camera
  std::vector<Pair> pairs_;
  int unpaired_ = 0;
  double load_ms_ = 0;          ///< waiting for images (wall clock)
  double decode_cpu_ms_ = 0;    ///< reading and decoding, CPU time of the thread that did it
  double frontend_cpu_ms_ = 0;  ///< the front end, CPU time of its thread
  std::future<LoadedPair> next_;  ///< read-ahead (declared last: joined first)
  size_t next_k_ = 0;
};

std::string TrackLengthJson(const frontend::FeatureTracks& tracks) {
  const std::vector<int> lengths = tracks.TrackLengths();
  std::vector<int> histogram(kTrackHistogramBins, 0);
  for (int n : lengths) ++histogram[static_cast<size_t>(std::min(n, kTrackHistogramBins) - 1)];
  std::ostringstream os;
  os << "{\"tracks\": " << lengths.size() << ", \"median\": " << Number(Percentile(lengths, 0.5))
     << ", \"p90\": " << Number(Percentile(lengths, 0.9)) << ", \"max\": "
     << (lengths.empty() ? 0 : *std::max_element(lengths.begin(), lengths.end())) << ", \"histogram\": [";
  for (size_t i = 0; i < histogram.size(); ++i) os << (i ? ", " : "") << histogram[i];
  os << "]}";
  return os.str();
}

std::string ImageFrameSource::ReportJson() const {
  const frontend::FrontendStats& s = frontend_->stats();
  const double frames = std::max<double>(1.0, static_cast<double>(s.frames));
  const std::vector<int>& per_frame = s.observations_per_frame;
  double sum = 0;
  for (int n : per_frame) sum += n;
  std::ostringstream os;
  os << "{\"source\": \"" << name_ << "\", \"frames\": " << s.frames << ", \"unpaired_frames\": " << unpaired_
     << ", \"features_per_frame\": {\"mean\": " << Number(sum / frames) << ", \"min\": "
     << (per_frame.empty() ? 0 : *std::min_element(per_frame.begin(), per_frame.end())) << ", \"max\": "
     << (per_frame.empty() ? 0 : *std::max_element(per_frame.begin(), per_frame.end())) << "}"
     << ", \"stereo_candidates\": " << s.stereo_candidates << ", \"stereo_inliers\": " << s.stereo_inliers
     << ", \"stereo_inlier_ratio\": "
     << Number(s.stereo_candidates ? static_cast<double>(s.stereo_inliers) / s.stereo_candidates : 0.0)
     << ", \"stereo_row_difference_median_px\": " << Number(s.MedianRowDifferencePx())
     << ", \"temporal_matches\": " << s.temporal_matches << ", \"rejected_reprojection\": " << s.rejected_reprojection
     << ", \"new_tracks\": " << s.new_tracks << ", \"reidentified\": " << s.reidentified
     << ", \"track_length\": " << TrackLengthJson(frontend_->tracks())
     << ", \"stage_ms\": {\"load\": " << Number(load_ms_ / frames) << ", \"detect\": "
     << Number(s.time.detect_ms / frames) << ", \"stereo_match\": " << Number(s.time.stereo_ms / frames)
     << ", \"temporal_match\": " << Number(s.time.temporal_ms / frames) << ", \"reject\": "
     << Number(s.time.reject_ms / frames) << ", \"frontend\": " << Number(s.time.total() / frames) << "}"
     << ", \"cpu_ms\": {\"decode\": " << Number(decode_cpu_ms_ / frames)
     << ", \"frontend\": " << Number(frontend_cpu_ms_ / frames) << "}}";
  return os.str();
}

}  // namespace

std::unique_ptr<FrameSource> MakeImageFrameSource(const FrontendOptions& options, const EurocDataset& dataset,
                                                  const frontend::StereoRectifier& rectifier) {
  if (!dataset.has_images) {
    throw std::runtime_error(dataset.root + ": the '" + options.frontend +
                             "' front end needs the images of mav0/cam0/data and mav0/cam1/data, and there are none "
                             "(render some with `vio simulate --camera=images`, or use --frontend=features)");
  }
  return std::make_unique<ImageFrameSource>(options, dataset, rectifier);
}

}  // namespace vio::tools
