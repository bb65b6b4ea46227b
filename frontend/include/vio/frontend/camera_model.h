#pragma once
// A calibrated camera with lens distortion, as in EuRoC camN/sensor.yaml.
//
// Two distortion models (both in normalized image coordinates, pixel centres
// at integer coordinates, OpenCV convention):
//
//  * "radial-tangential" (pinhole + k1 k2 p1 p2, OpenCV/EuRoC):
//      x = X/Z, y = Y/Z, r^2 = x^2 + y^2
//      x_d = x (1 + k1 r^2 + k2 r^4) + 2 p1 x y + p2 (r^2 + 2 x^2)
//      y_d = y (1 + k1 r^2 + k2 r^4) + p1 (r^2 + 2 y^2) + 2 p2 x y
//  * "equidistant" (Kannala-Brandt, OpenCV fisheye, k1..k4):
//      theta = atan2(sqrt(X^2 + Y^2), Z)
//      theta_d = theta (1 + k1 theta^2 + k2 theta^4 + k3 theta^6 + k4 theta^8)
//      (x_d, y_d) = theta_d (X, Y) / sqrt(X^2 + Y^2)
//  then u = fu x_d + cu, v = fv y_d + cv.
//
// Both radial maps are only invertible while they increase with the radius:
// the model computes that valid radius once (`max_valid_radius`) and treats
// points beyond it as not projectable, so a point far outside the field of
// view can never fold back into the image.
#include <optional>

#include <Eigen/Core>

#include "vio/estimator/types.h"

namespace vio::frontend {

class CameraModel {
 public:
  enum class Distortion { kRadialTangential, kEquidistant };

  /// Throws std::invalid_argument naming the bad field (unknown distortion
  /// model, non-positive focal length or image size).
  explicit CameraModel(const CameraCalibration& calibration);

  /// Distorted pixel of a point in the camera frame; nullopt when the point
  /// is behind the camera (Z <= 0 for radial-tangential), beyond the valid
  /// distortion radius, or outside the image [0, width-1] x [0, height-1].
  std::optional<Eigen::Vector2d> Project(const Eigen::Vector3d& p_c) const;

  /// As Project but without the image-bounds check.
  std::optional<Eigen::Vector2d> ProjectUnbounded(const Eigen::Vector3d& p_c) const;

  /// Unit bearing (camera frame) of a distorted pixel, by Newton iteration on
  /// the distortion to 1e-12 in normalized coordinates; nullopt when the
  /// iteration does not converge inside the valid radius.
  std::optional<Eigen::Vector3d> Unproject(const Eigen::Vector2d& uv_px) const;

  /// Undistorted normalized point (X/Z, Y/Z) of a distorted pixel; nullopt as
  /// Unproject, or when the bearing is not in front (Z <= 0).
  std::optional<Eigen::Vector2d> UnprojectToNormalized(const Eigen::Vector2d& uv_px) const;

  /// True when the pixel lies in [border, width-1-border] x [border, height-1-border].
  bool InImage(const Eigen::Vector2d& uv_px, double border_px = 0.0) const;

  Distortion distortion() const { return distortion_; }
  const CameraCalibration& calibration() const { return calibration_; }
  int width() const { return calibration_.width; }
  int height() const { return calibration_.height; }
  /// Largest normalized radius r (radial-tangential) or angle theta [rad]
  /// (equidistant) where the radial distortion is still increasing.
  double max_valid_radius() const { return max_valid_radius_; }

 private:
  /// Distorted normalized point of an undistorted normalized point (rad-tan).
  Eigen::Vector2d DistortRadTan(const Eigen::Vector2d& xy, Eigen::Matrix2d* d_xyd_d_xy) const;
  /// theta_d(theta) of the equidistant model and its derivative.
  double DistortTheta(double theta, double* d_thetad_d_theta) const;
  std::optional<Eigen::Vector3d> UndistortRadTan(const Eigen::Vector2d& xy_d) const;
  std::optional<Eigen::Vector3d> UndistortEquidistant(const Eigen::Vector2d& xy_d) const;
  Eigen::Vector2d ToPixel(const Eigen::Vector2d& xy_d) const;

  CameraCalibration calibration_;
  Distortion distortion_ = Distortion::kRadialTangential;
  double max_valid_radius_ = 0.0;
};

}  // namespace vio::frontend
