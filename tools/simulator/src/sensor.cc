#include "vio/simulator/sensor.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <glog/logging.h>

#include "hash.h"

namespace vio::tools {
namespace {

constexpr double kTwoPi = 6.283185307179586;
/// The faster exposure component: period ratio and relative amplitude.
constexpr double kFastPeriodRatio = 1.0 / 2.7;
constexpr double kFastAmplitude = 0.4;

void Require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("rendered images: " + what);
}

}  // namespace

void CheckSensorOptions(const SensorOptions& o) {
  Require(o.exposure_ms >= 0.0 && o.exposure_ms <= 100.0, "exposure_ms must be in [0, 100] ms, got " + std::to_string(o.exposure_ms));
  Require(o.exposure_variation >= 0.0 && o.exposure_variation <= 2.0,
          "exposure_variation must be in [0, 2], got " + std::to_string(o.exposure_variation));
  Require(o.exposure_period_s > 0.0, "exposure_period must be positive [s], got " + std::to_string(o.exposure_period_s));
  Require(o.vignetting >= 0.0 && o.vignetting < 1.0, "vignetting must be in [0, 1), got " + std::to_string(o.vignetting));
  Require(o.read_noise >= 0.0 && o.read_noise <= 50.0, "image_noise (read noise) must be in [0, 50] grey levels, got " + std::to_string(o.read_noise));
  Require(o.shot_noise >= 0.0 && o.shot_noise <= 50.0, "shot_noise must be in [0, 50] grey levels, got " + std::to_string(o.shot_noise));
  Require(o.blur_step_px > 0.0, "blur_step_px must be positive, got " + std::to_string(o.blur_step_px));
  Require(o.max_blur_samples >= 1 && o.max_blur_samples <= 64,
          "max_blur_samples must be in [1, 64], got " + std::to_string(o.max_blur_samples));
  Require(o.blur_min_depth_m > 0.0, "blur_min_depth_m must be positive, got " + std::to_string(o.blur_min_depth_m));
}

double ExposureFactor(const SensorOptions& options, std::uint64_t seed, double t_s) {
  if (options.exposure_variation == 0.0) return 1.0;
  const std::uint64_t h = Mix(seed ^ 0x6578706f73757265ULL);
  const double phase_slow = kTwoPi * UnitFromBits(h), phase_fast = kTwoPi * UnitFromBits(h >> 8);
  const double w = kTwoPi / options.exposure_period_s;
  const double s = (std::sin(w * t_s + phase_slow) + kFastAmplitude * std::sin(w / kFastPeriodRatio * t_s + phase_fast)) /
                   (1.0 + kFastAmplitude);
  return std::exp(options.exposure_variation * s);
}

double ImageMotionPx(const Eigen::Isometry3d& T_w_c0, const Eigen::Isometry3d& T_w_c1, double focal_px,
                     const SensorOptions& options) {
  const Eigen::AngleAxisd rotation(T_w_c0.linear().transpose() * T_w_c1.linear());
  const double translation = (T_w_c1.translation() - T_w_c0.translation()).norm();
  return focal_px * (std::abs(rotation.angle()) + translation / options.blur_min_depth_m);
}

std::vector<Eigen::Isometry3d> ExposurePoses(
    const std::function<std::optional<Eigen::Isometry3d>(double)>& pose_at, double exposure_s, double focal_px,
    const SensorOptions& options) {
  const std::optional<Eigen::Isometry3d> mid = pose_at(0.0);
  CHECK(mid.has_value()) << "the frame's own pose must be known";
  if (exposure_s <= 0.0 || options.max_blur_samples == 1) return {*mid};
  const Eigen::Isometry3d start = pose_at(-0.5 * exposure_s).value_or(*mid);
  const Eigen::Isometry3d end = pose_at(0.5 * exposure_s).value_or(*mid);
  const double motion_px = ImageMotionPx(start, end, focal_px, options);
  const int n = std::clamp(static_cast<int>(std::ceil(motion_px / options.blur_step_px)), 1, options.max_blur_samples);
  if (n == 1) return {*mid};
  std::vector<Eigen::Isometry3d> poses;
  for (int k = 0; k < n; ++k) poses.push_back(pose_at(exposure_s * ((k + 0.5) / n - 0.5)).value_or(*mid));
  return poses;
}

cv::Mat VignettingMap(const CameraCalibration& camera, double vignetting) {
  cv::Mat map(camera.height, camera.width, CV_32FC1);
  const double cu = camera.intrinsics[2], cv_ = camera.intrinsics[3];
  const double du = std::max(cu, camera.width - 1 - cu), dv = std::max(cv_, camera.height - 1 - cv_);
  const double inv_r2 = 1.0 / (du * du + dv * dv);
  for (int v = 0; v < camera.height; ++v) {
    float* row = map.ptr<float>(v);
    for (int u = 0; u < camera.width; ++u) {
      const double r2 = ((u - cu) * (u - cu) + (v - cv_) * (v - cv_)) * inv_r2;
      row[u] = static_cast<float>(1.0 - vignetting * r2);
    }
  }
  return map;
}

void ExposeImage(const cv::Mat& radiance, double brightness, const cv::Mat& vignette, const SensorOptions& options,
                 std::uint64_t noise_key, cv::Mat* image) {
  CHECK(image != nullptr);
  CHECK_EQ(radiance.type(), CV_32FC1);
  CHECK(vignette.empty() || (vignette.size() == radiance.size() && vignette.type() == CV_32FC1));
  image->create(radiance.size(), CV_8UC1);
  const float gain = static_cast<float>(brightness);
  const float read_var = static_cast<float>(options.read_noise * options.read_noise);
  const float shot_var_per_grey = static_cast<float>(options.shot_noise * options.shot_noise / 128.0);
  for (int v = 0; v < radiance.rows; ++v) {
    const float* in = radiance.ptr<float>(v);
    const float* vig = vignette.empty() ? nullptr : vignette.ptr<float>(v);
    std::uint8_t* out = image->ptr<std::uint8_t>(v);
    for (int u = 0; u < radiance.cols; ++u) {
      const float signal = in[u] * gain * (vig != nullptr ? vig[u] : 1.0f);
      const float sigma = std::sqrt(read_var + shot_var_per_grey * std::max(signal, 0.0f));
      const std::uint64_t index = static_cast<std::uint64_t>(v) * radiance.cols + u;
      const float grey = sigma > 0.0f ? signal + sigma * HashNormal(PixelHash(noise_key, index)) : signal;
      out[u] = static_cast<std::uint8_t>(std::clamp(grey + 0.5f, 0.0f, 255.0f));
    }
  }
}

}  // namespace vio::tools
