#include "vio/simulator/image_statistics.h"

#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <map>
#include <sstream>

#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "vio/dataset/euroc_dataset.h"
#include "vio/dataset/image_file.h"
#include "vio/frontend/stereo_frontend.h"

namespace vio::tools {
namespace {

struct PairFiles {
  Timestamp t_ns = 0;
  std::string left, right;
};

std::vector<PairFiles> StereoPairs(const EurocDataset& dataset, int max_frames) {
  std::map<Timestamp, std::string> right;
  for (const CameraFrame& f : dataset.frames[1]) right[f.t_ns] = f.filename;
  std::vector<PairFiles> pairs;
  for (const CameraFrame& f : dataset.frames[0]) {
    if (static_cast<int>(pairs.size()) >= max_frames) break;
    const auto it = right.find(f.t_ns);
    if (it == right.end()) continue;
    pairs.push_back({f.t_ns, dataset.root + "/mav0/cam0/data/" + f.filename,
                     dataset.root + "/mav0/cam1/data/" + it->second});
  }
  return pairs;
}

cv::Mat ReadGrey(const std::string& path) {
  cv::Mat image = ImageRead(path, cv::IMREAD_GRAYSCALE);
  if (image.empty()) throw DatasetError(path + ": cannot read the image");
  return image;
}

// Mean of (I(u+1) - I(u-1))^2 / 4 + (I(v+1) - I(v-1))^2 / 4 over the interior.
double GradientEnergy(const cv::Mat& image) {
  cv::Mat gx, gy;
  const cv::Mat kernel = (cv::Mat_<float>(1, 3) << -0.5f, 0.0f, 0.5f);
  cv::filter2D(image, gx, CV_32F, kernel);
  cv::filter2D(image, gy, CV_32F, kernel.t());
  const cv::Rect interior(1, 1, image.cols - 2, image.rows - 2);
  return cv::mean(gx(interior).mul(gx(interior)) + gy(interior).mul(gy(interior)))[0];
}

double Median(std::vector<int> values) {
  if (values.empty()) return 0.0;
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

}  // namespace

ImageStatistics MeasureImageStatistics(const std::string& dataset_dir, const ImageStatisticsOptions& options) {
  EurocReadOptions read;
  read.read_features = false;
  const EurocDataset dataset = ReadEuroc(dataset_dir, read);
  const std::vector<PairFiles> pairs = StereoPairs(dataset, options.max_frames);
  if (pairs.empty()) throw DatasetError(dataset_dir + ": no stereo image pair (cam0 and cam1 rows with the same stamp)");
  FrontendOptions frontend_options = options.frontend;
  frontend_options.frontend = "klt";
  const frontend::StereoRectifier rectifier(dataset.cameras[0], dataset.cameras[1]);
  const std::unique_ptr<frontend::StereoFrontend> klt = frontend::MakeStereoFrontend(frontend_options, rectifier);
  const cv::Ptr<cv::BRISK> brisk = cv::BRISK::create(options.brisk_threshold);
  ImageStatistics stats;
  stats.name = std::filesystem::path(dataset_dir).lexically_normal().filename().string();
  if (stats.name.empty()) stats.name = std::filesystem::path(dataset_dir).parent_path().filename().string();
  for (const PairFiles& pair : pairs) {
    const cv::Mat left = ReadGrey(pair.left), right = ReadGrey(pair.right);
    cv::Scalar mean, stddev;
    cv::meanStdDev(left, mean, stddev);
    stats.mean_grey += mean[0];
    stats.contrast += stddev[0];
    stats.gradient_energy += GradientEnergy(left);
    std::vector<cv::KeyPoint> corners;
    cv::FAST(left, corners, options.fast_threshold, true);
    stats.fast_corners += static_cast<double>(corners.size());
    brisk->detect(left, corners);
    stats.brisk_corners += static_cast<double>(corners.size());
    stats.klt_features += static_cast<double>(klt->Process(pair.t_ns, left, right, {}).observations.size());
    ++stats.frames;
  }
  for (double* sum : {&stats.mean_grey, &stats.contrast, &stats.gradient_energy, &stats.fast_corners,
                      &stats.brisk_corners, &stats.klt_features}) {
    *sum /= stats.frames;
  }
  stats.klt_track_length = Median(klt->tracks().TrackLengths());
  stats.klt_row_difference_px = klt->stats().MedianRowDifferencePx();
  return stats;
}

std::string StatisticsTable(const std::vector<ImageStatistics>& rows) {
  std::ostringstream os;
  os << "| sequence | frames | mean grey | contrast (std) | gradient energy | FAST corners | BRISK corners | "
        "KLT stereo features | KLT median track [frames] | KLT stereo row difference [px] |\n"
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  os << std::fixed;
  for (const ImageStatistics& r : rows) {
    os << "| " << r.name << " | " << r.frames << " | " << std::setprecision(1) << r.mean_grey << " | " << r.contrast
       << " | " << std::setprecision(0) << r.gradient_energy << " | " << r.fast_corners << " | " << r.brisk_corners
       << " | " << r.klt_features << " | " << std::setprecision(1) << r.klt_track_length << " | "
       << std::setprecision(3) << r.klt_row_difference_px << " |\n";
  }
  return os.str();
}

}  // namespace vio::tools
