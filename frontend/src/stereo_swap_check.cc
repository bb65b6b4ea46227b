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
/// The corners are sought on the image shrunk by this factor (the row search
/// then compares full-resolution patches): goodFeaturesToTrack on a whole
/// 752x480 image costs 35 M instructions, two per pair, more than the KLT
/// front end's tracking of a frame; on the half image 8 M. On the real clips
/// the matches as given / exchanged are 244/14 (static) and 261/12 (flight)
/// against 240/14 and 266/7 on the whole image [count].
constexpr int kCornerShrink = 2;

}  // namespace

StereoSwapCheck::StereoSwapCheck(const StereoRectifier& rectifier)
    : rectifier_(rectifier), row_search_(rectifier, kPatchPx, kMaxDisparityPx, kMinNcc) {}

// `first` is taken as the left image, `second` as the right (rectified with cam0's and cam1's
// calibration): exchanged, each with the other camera's, close enough on a rig whose two cameras are
// alike, which is what makes an exchange go unnoticed.
int StereoSwapCheck::Matches(const cv::Mat& first, const cv::Mat& second) const {
  std::vector<cv::Point2f> corners;
  cv::Mat shrunk;
  cv::resize(first, shrunk, cv::Size(), 1.0 / kCornerShrink, 1.0 / kCornerShrink, cv::INTER_AREA);
  cv::goodFeaturesToTrack(shrunk, corners, kCornersPerImage, kCornerQuality, kCornerSpacingPx / kCornerShrink);
  int matches = 0;
  for (const cv::Point2f& c : corners) {
    // Shrunk pixel i covers full pixels kCornerShrink * i .. kCornerShrink * (i + 1) - 1.
    const double half_step = 0.5 * (kCornerShrink - 1);
    const Eigen::Vector2d uv(kCornerShrink * c.x + half_step, kCornerShrink * c.y + half_step);
    const std::optional<Eigen::Vector2d> rectified = rectifier_.Rectify(0, uv);
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
