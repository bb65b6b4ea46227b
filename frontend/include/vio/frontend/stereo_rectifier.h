#pragma once
// Stereo rectification of a calibrated camera pair (paper §5.4): both
// rectified cameras share one pinhole (f, cx, cy), their rows are epipolar
// lines, and the right one sits at +baseline along the left one's x axis.
//
// R_k (the rotation from camera k to rectified camera k) and P_k come from
// OpenCV's cv::stereoRectify (cv::fisheye::stereoRectify for equidistant
// cameras) with CALIB_ZERO_DISPARITY, the input image size as output size and
// alpha = 0 (fisheye: balance = 0): the rectified image is zoomed so that
// every rectified pixel maps to a valid source pixel (no black borders); the
// price is a slightly narrower field of view.
//
// A distorted pixel of camera k maps to the rectified image as
//   bearing = CameraModel_k.Unproject(uv)      (iterative undistortion)
//   p       = R_k * bearing                      (rectified camera k frame)
//   uv_rect = (f p.x / p.z + cx, f p.y / p.z + cy)
// which is what cv::undistortPoints(uv, K_k, D_k, R_k, P_k) computes;
// RectifyWithOpenCv exposes the latter so the two can be compared.
#include <array>
#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "vio/estimator/types.h"
#include "vio/frontend/camera_model.h"

namespace vio::frontend {

class StereoRectifier {
 public:
  /// cam0 is the left camera, cam1 the right; both T_b_c are used. Throws
  /// std::invalid_argument when the models differ, the image sizes differ or
  /// the cameras are not side by side (cam1 not to the right of cam0).
  StereoRectifier(const CameraCalibration& cam0, const CameraCalibration& cam1);

  /// The rectified geometry the estimator projects with.
  const RectifiedStereo& rectified() const { return rectified_; }

  /// Rectified pixel of a distorted pixel of camera `camera` (0 or 1);
  /// nullopt when the pixel cannot be undistorted or lands behind the
  /// rectified camera.
  std::optional<Eigen::Vector2d> Rectify(int camera, const Eigen::Vector2d& uv_px) const;

  /// The same mapping computed by cv::undistortPoints with R_k, P_k (iterated
  /// to convergence), for cross-checking.
  std::vector<Eigen::Vector2d> RectifyWithOpenCv(int camera,
                                                 const std::vector<Eigen::Vector2d>& uv_px) const;

  /// The stereo measurement (u_L, u_R, v) of a landmark seen at distorted
  /// pixels uv0 (left) and uv1 (right): v is the mean of the two rectified
  /// rows (paper §5.4). nullopt when either pixel cannot be rectified.
  std::optional<Eigen::Vector3d> RectifyStereo(const Eigen::Vector2d& uv0_px,
                                               const Eigen::Vector2d& uv1_px) const;

  /// Remap tables (CV_32FC1 map_x, map_y) producing the rectified image of
  /// camera `camera` with cv::remap.
  std::pair<cv::Mat, cv::Mat> RectificationMaps(int camera) const;

  /// Rotation from camera k to rectified camera k (OpenCV's R1 / R2).
  const Eigen::Matrix3d& R_rect_cam(int camera) const { return R_rect_cam_[Index(camera)]; }
  /// Projection matrix of rectified camera k (OpenCV's P1 / P2) [px].
  const Eigen::Matrix<double, 3, 4>& P(int camera) const { return P_[Index(camera)]; }
  const CameraModel& camera_model(int camera) const { return models_[Index(camera)]; }

 private:
  static std::size_t Index(int camera);
  void ComputeRectification();

  std::array<CameraModel, 2> models_;
  std::array<Eigen::Matrix3d, 2> R_rect_cam_;
  std::array<Eigen::Matrix<double, 3, 4>, 2> P_;
  RectifiedStereo rectified_;
};

}  // namespace vio::frontend
