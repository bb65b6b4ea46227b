#include "frame_source_images.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <time.h>

#include <glog/logging.h>
#include <opencv2/imgcodecs.hpp>

#include "vio/frontend/stereo_frontend.h"
#include "vio/frontend/stereo_swap_check.h"
#include "vio/frontend/track_drawing.h"
#include "pair_pipeline.h"
#include "vio/dataset/image_file.h"
#include "vio/dataset/ros2_dataset.h"
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

// The pipeline's threads for the option's value: 0 picks 2 when this process
// may run on two processors or more, else 1 (a second thread would only take
// the tracking's core).
int PipelineThreads(int option) {
  if (option != 0) return option;
  const int threads = AvailableCpus() >= 2 ? 2 : 1;
  LOG(INFO) << "pipeline_threads=0: " << threads << " (" << AvailableCpus() << " processors available)";
  return threads;
}

class ImageFrameSource final : public FrameSource {
 public:
  ImageFrameSource(const FrontendOptions& options, const EurocDataset& dataset,
                   const frontend::StereoRectifier& rectifier)
      : name_(options.frontend),
        mav0_(dataset.root + "/mav0"),
        debug_dir_(options.debug_images),
        frontend_(frontend::MakeStereoFrontend(options, rectifier)),
        swap_check_(rectifier),
        threads_(PipelineThreads(options.pipeline_threads)) {
    for (int i = 0; i < 2; ++i) {
      filenames_[i].reserve(dataset.frames[i].size());
      for (const CameraFrame& f : dataset.frames[i]) filenames_[i].push_back(f.filename);
      if (dataset.image_bag.empty()) continue;
      if (dataset.ros2_images) {
        if (!ros2_images_) ros2_images_.emplace(dataset);
      } else if (IsRos2BagPath(dataset.image_bag)) {
        ros2_readers_[i].emplace(dataset.image_bag, dataset.image_topics[i]);
      } else {
        bag_readers_[i].emplace(dataset.image_bag, dataset.image_topics[i]);
      }
    }
    PairFrames(dataset);
    if (!debug_dir_.empty()) std::filesystem::create_directories(debug_dir_);
    pipeline_.emplace(pairs_.size(), threads_, [this](PipelinePair* slot) { MakePair(slot); });
  }

  size_t size() const override { return pairs_.size(); }
  Timestamp time(size_t k) const override { return pairs_[k].t_ns; }

  // Pair k from the pipeline's first stage, tracked with the estimator's
  // prediction (the second stage, on this thread).
  StereoFrame Frame(size_t k, const Estimator& estimator) override {
    const Pair& pair = pairs_[k];
    const auto start = std::chrono::steady_clock::now();
    PipelinePair slot = pipeline_->Take(k);
    // One thread: Take prepared the pair, which is the front end's time;
    // two: the waiting for the reader thread is all Take cost here.
    const double prepare_here_ms = threads_ == 1 ? slot.prepare_wall_ms : 0.0;
    load_ms_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() -
                prepare_here_ms;
    decode_cpu_ms_ += slot.decode_cpu_ms;
    prepare_cpu_ms_ += slot.prepare_cpu_ms;
    prepare_wall_ms_ += slot.prepare_wall_ms;
    frontend::FramePrior prior;
    prior.T_w_b = estimator.PredictBodyPose(pair.t_ns);
    prior.landmarks = &estimator.window().landmarks();
    const double cpu_start_ms = ThreadCpuMs();
    swap_check_.Add(slot.pair->left, slot.pair->right);
    StereoFrame frame = frontend_->Process(pair.t_ns, slot.pair.get(), prior);
    frontend_->AddPrepareTime(prepare_here_ms);
    frontend_cpu_ms_ += ThreadCpuMs() - cpu_start_ms;
    if (!debug_dir_.empty()) WriteDebugImage(pair.t_ns, slot.pair->left, slot.pair->right);
    pipeline_->Give(std::move(slot));
    return frame;
  }

  std::string ReportJson() const override;
  std::string InputProblem() const override { return swap_check_.problem(); }

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

  // The pipeline's first stage for pair slot->k: read, decode, prepare (into
  // the slot's pair, reusing the memory of its pyramids). With two threads it runs
  // on the reader thread and finds the whole image's corners there.
  void MakePair(PipelinePair* slot) {
    frontend::PreparedPair* prepared = slot->pair.get();
    double start_ms = ThreadCpuMs();
    Load(0, pairs_[slot->k].left, &prepared->left);
    Load(1, pairs_[slot->k].right, &prepared->right);
    slot->decode_cpu_ms = ThreadCpuMs() - start_ms;
    const auto wall_start = std::chrono::steady_clock::now();
    start_ms = ThreadCpuMs();
    const cv::Mat left = prepared->left, right = prepared->right;
    frontend_->Prepare(left, right, /*with_corners=*/threads_ == 2, prepared);
    slot->prepare_cpu_ms = ThreadCpuMs() - start_ms;
    slot->prepare_wall_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wall_start).count();
  }

  // The image of one data.csv row: a file under camN/data/, or a bag message.
  void Load(int camera, size_t row, cv::Mat* image) {
    if (bag_readers_[camera]) {
      *image = bag_readers_[camera]->Read(row);
      return;
    }
    if (ros2_images_) {
      *image = ros2_images_->Read(camera, row);
      return;
    }
    if (ros2_readers_[camera]) {
      *image = ros2_readers_[camera]->Read(row);
      return;
    }
    const std::string path = mav0_ + "/cam" + std::to_string(camera) + "/data/" + filenames_[camera][row];
    *image = ReadGreyImage(path);
    if (image->empty()) throw std::runtime_error(path + ": cannot read the image");
  }

  void WriteDebugImage(Timestamp t_ns, const cv::Mat& left, const cv::Mat& right) {
    const std::string path = debug_dir_ + "/" + std::to_string(t_ns) + ".png";
    if (!ImageWrite(path, drawer_.Draw(left, right, frontend_->features()))) {
      throw std::runtime_error(path + ": cannot write the debug image");
    }
  }

  std::string name_;
  std::string mav0_;
  std::string debug_dir_;
  std::unique_ptr<frontend::StereoFrontend> frontend_;
  frontend::StereoSwapCheck swap_check_;  ///< on the first pairs
  frontend::TrackDrawer drawer_;
  std::vector<std::string> filenames_[2];
  std::optional<BagImageReader> bag_readers_[2];  ///< images from a ROS 1 bag: one sequential reader per camera
  std::optional<Ros2StereoImageReader> ros2_images_;  ///< or from a ROS 2 recording read by ReadRos2Bag
  std::optional<Ros2ImageReader> ros2_readers_[2];    ///< or from one read otherwise
  std::vector<Pair> pairs_;
  int unpaired_ = 0;
  double load_ms_ = 0;          ///< waiting for images (wall clock)
  double decode_cpu_ms_ = 0;    ///< reading and decoding, CPU time of the thread that did it
  double prepare_cpu_ms_ = 0;   ///< Prepare (pyramids, corners), CPU time of the thread that did it
  double prepare_wall_ms_ = 0;  ///< Prepare, wall time on the thread that did it
  double frontend_cpu_ms_ = 0;  ///< the front end's tracking, CPU time of its thread
  int threads_;                 ///< of the pipeline: 1 or 2
  std::optional<PairPipeline> pipeline_;  ///< declared last: its reader thread stops first
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
     << ", \"row_searches\": " << s.row_searches
     << ", \"track_length\": " << TrackLengthJson(frontend_->tracks())
     << ", \"stage_ms\": {\"load\": " << Number(load_ms_ / frames) << ", \"detect\": "
     << Number(s.time.detect_ms / frames) << ", \"stereo_match\": " << Number(s.time.stereo_ms / frames)
     << ", \"temporal_match\": " << Number(s.time.temporal_ms / frames) << ", \"reject\": "
     << Number(s.time.reject_ms / frames) << ", \"prepare\": " << Number(prepare_wall_ms_ / frames)
     << ", \"frontend\": " << Number(s.time.total() / frames) << "}"
     << ", \"cpu_ms\": {\"decode\": " << Number(decode_cpu_ms_ / frames)
     << ", \"prepare\": " << Number(prepare_cpu_ms_ / frames)
     << ", \"frontend\": " << Number((frontend_cpu_ms_ + prepare_cpu_ms_) / frames) << "}"
     << ", \"pipeline_threads\": " << threads_ << "}";
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
