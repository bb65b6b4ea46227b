#include "vio/frontend/track_drawing.h"

#include <string>

#include <opencv2/imgproc.hpp>

namespace vio::frontend {

cv::Mat TrackDrawer::Draw(const cv::Mat& left, const cv::Mat& right, const std::vector<FrameFeature>& features) {
  cv::Mat grey, image;
  cv::hconcat(left, right, grey);
  cv::cvtColor(grey, image, cv::COLOR_GRAY2BGR);
  const cv::Point2f right_shift(static_cast<float>(left.cols), 0.0f);
  std::unordered_map<std::int64_t, std::deque<cv::Point2f>> tails;
  int stereo = 0;
  for (const FrameFeature& f : features) {
    const cv::Point2f uv0(static_cast<float>(f.uv0_px.x()), static_cast<float>(f.uv0_px.y()));
    std::deque<cv::Point2f> tail = std::move(tails_[f.id.value]);
    tail.push_back(uv0);
    while (static_cast<int>(tail.size()) > tail_frames_) tail.pop_front();
    for (size_t i = 1; i < tail.size(); ++i) cv::line(image, tail[i - 1], tail[i], cv::Scalar(255, 128, 0), 1);
    tails[f.id.value] = std::move(tail);
    if (!f.stereo) {
      cv::circle(image, uv0, 2, cv::Scalar(0, 0, 255), cv::FILLED);
      continue;
    }
    ++stereo;
    const cv::Scalar colour = f.tracked ? cv::Scalar(0, 255, 0) : cv::Scalar(0, 255, 255);
    const cv::Point2f uv1(static_cast<float>(f.uv1_px.x()), static_cast<float>(f.uv1_px.y()));
    cv::circle(image, uv0, 3, colour, 1);
    cv::circle(image, uv1 + right_shift, 3, colour, 1);
  }
  tails_ = std::move(tails);
  cv::putText(image, std::to_string(stereo) + " stereo / " + std::to_string(features.size()) + " features",
              cv::Point(8, 20), cv::FONT_HERSHEY_SIMPLEX, 0.6, cv::Scalar(0, 255, 255), 1);
  return image;
}

}  // namespace vio::frontend
