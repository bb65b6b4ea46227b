#pragma once
// What a real global-shutter camera adds to the scene's radiance (the
// renderer's grey levels at the nominal exposure):
//   exposure  auto exposure hunting: exposure time and brightness vary
//             smoothly over time by a factor exp(+-exposure_variation);
//   blur      the image integrates the scene over the exposure time along the
//             true motion (sub-frames spaced so that no pixel moves more than
//             blur_step_px between two; the frame stamp is mid-exposure);
//   vignette  brightness falls with the squared distance from the principal
//             point, by `vignetting` at the farthest image corner;
//   noise     per pixel, shot noise (variance proportional to the signal)
//             plus read noise, then rounding to 8 bits.
// Everything is a function of the seed, the frame and the pixel.
#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "vio/estimator/types.h"

namespace vio::tools {

struct SensorOptions {
  /// Nominal exposure time [ms]; 0 renders instantaneous frames (no motion blur).
  double exposure_ms = 5.0;
  /// Auto-exposure changes: exposure and brightness vary by up to exp(+-this) [ln factor].
  double exposure_variation = 0.25;
  /// Period of the slowest exposure change [s].
  double exposure_period_s = 8.0;
  /// Brightness loss at the farthest image corner [fraction, 0..1).
  double vignetting = 0.3;
  /// Read noise, standard deviation [grey levels].
  double read_noise = 1.0;
  /// Shot noise at grey level 128, standard deviation [grey levels] (variance proportional to the signal).
  double shot_noise = 1.5;
  /// Largest image motion between two sub-frames of the exposure [px].
  double blur_step_px = 0.5;
  /// Most sub-frames rendered per exposure (1: no motion blur).
  int max_blur_samples = 12;
  /// Nearest scene depth assumed when converting translation to image motion [m].
  double blur_min_depth_m = 1.0;
};

/// Throws std::invalid_argument naming the first option out of range.
void CheckSensorOptions(const SensorOptions& options);

/// Brightness (and exposure time) factor of the frame at t_s [s] (auto
/// exposure): exp(exposure_variation * s(t)), s a smooth function in [-1, 1]
/// made of two sinusoids with seeded phases.
double ExposureFactor(const SensorOptions& options, std::uint64_t seed, double t_s);

/// Largest image motion [px] of a camera moving from T_w_c0 to T_w_c1 (focal
/// length `focal_px`): rotation angle plus translation over blur_min_depth_m.
double ImageMotionPx(const Eigen::Isometry3d& T_w_c0, const Eigen::Isometry3d& T_w_c1, double focal_px,
                     const SensorOptions& options);

/// Camera poses of the sub-frames of one exposure: `pose_at(offset_s)` gives
/// the camera pose at an offset from the frame stamp (nullopt: unknown, the
/// frame's pose is used); the exposure [s] is split into N equal parts
/// (N from the image motion across it, 1..max_blur_samples) sampled at
/// their centres.
std::vector<Eigen::Isometry3d> ExposurePoses(
    const std::function<std::optional<Eigen::Isometry3d>(double)>& pose_at, double exposure_s, double focal_px,
    const SensorOptions& options);

/// Per-pixel brightness factor of the vignetting (CV_32FC1, width x height).
cv::Mat VignettingMap(const CameraCalibration& camera, double vignetting);

/// The 8-bit image (CV_8UC1) of `radiance` (CV_32FC1, grey at nominal
/// exposure) times `brightness` times `vignette` (same size; empty: none),
/// with shot and read noise from the hash of (noise_key, pixel).
void ExposeImage(const cv::Mat& radiance, double brightness, const cv::Mat& vignette, const SensorOptions& options,
                 std::uint64_t noise_key, cv::Mat* image);

}  // namespace vio::tools
