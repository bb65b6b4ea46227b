#include "vio/frontend/stereo_swap_check.h"

#include <sstream>
#include <vector>

#include <glog/logging.h>
#include <opencv2/imgproc.hpp>

namespace vio::frontend {
namespace {

constexpr int kPatchPx = 11;
constexpr double kMaxDisparityPx = 128;
constexpr double kMinNcc = 0.85;
constexpr double kCornerQuality = 0.01;
constexpr double kCornerSpacingPx = 20;

}  // namespace

StereoSwapCheck::StereoSwapCheck(const StereoRectifier& rectifier)
    : rectifier_(rectifier), row_search_(rectifier, kPatchPx, kMaxDisparityPx, kMinNcc) {}

// `first` is taken as the left image, `second` as the right (rectified with cam0's and cam1's
// calibration): exchanged, each with the other camera's, close enough on a rig whose two cameras are
// alike, which is what makes an exchange go unnoticed.
int StereoSwapCheck::Matches(const cv::Mat& first, const cv::Mat& second) const {
  std::vector<cv::Point2f> corners;
  cv::goodFeaturesToTrack(first, corners, kCornersPerImage, kCornerQuality, kCornerSpacingPx);
  int matches = 0;
  for (const cv::Point2f& c : corners) {
    const std::optional<Eigen::Vector2d> rectified = rectifier_.Rectify(0, Eigen::Vector2d(c.x, c.y));
    if (!rectified) continue;
    const std::optional<double> disparity = row_search_.Disparity(first, second, *rectified);
    matches += disparity && *disparity > kMinDisparityPx;
  }
  return matches;
}

void StereoSwapCheck::Add(const cv::Mat& cam0, const cv::Mat& cam1) {
  if (decided_ || cam0.empty() || cam1.empty()) return;
  ++frames_;
  as_given_ += Matches(cam0, cam1);
  exchanged_ += Matches(cam1, cam0);
  if (as_given_ + exchanged_ >= kDecisionMatches || frames_ >= kMaxFrames) Decide();
}

void StereoSwapCheck::Decide() {
  decided_ = true;
  if (exchanged_ >= kMinExchangedMatches && exchanged_ > kExchangedRatio * as_given_) {
    std::ostringstream why;
    why << "the stereo images match only with cam0 and cam1 exchanged (" << exchanged_ << " corner matches at a "
        << "positive disparity that way, " << as_given_ << " as given, over " << frames_ << " pairs): are the "
        << "cameras swapped? cam0 must be the left camera: check mav0/cam0/data against T_BS in cam0/cam1 "
           "sensor.yaml (or the image topics)";
    problem_ = why.str();
  }
  LOG(INFO) << "stereo swap check: " << as_given_ << " matches as given, " << exchanged_ << " exchanged, over "
            << frames_ << " pairs" << (problem_.empty() ? "" : ": exchanged");
}

}  // namespace vio::frontend
