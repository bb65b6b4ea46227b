#include "vio/frontend/camera_model.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace vio::frontend {
namespace {

constexpr int kMaxNewtonIterations = 100;
constexpr double kNewtonTolerance = 1e-12;  // normalized image units
constexpr double kRadTanRadiusCap = 20.0;   // normalized radius: ~87 degrees off axis
constexpr double kEquidistantThetaCap = M_PI - 1e-6;  // [rad]

using Distortion = CameraModel::Distortion;

// Smallest radius in (0, cap] where the derivative `d_radial(r)` of a radial
// map stops being positive (scan in steps of cap / 20000, then the last good
// sample); `cap` when it never does.
template <class Derivative>
double FirstNonIncreasingRadius(Derivative d_radial, double cap) {
  constexpr int kSteps = 20000;
  const double step = cap / kSteps;
  for (int i = 1; i <= kSteps; ++i) {
    if (d_radial(i * step) <= 0.0) return (i - 1) * step;
  }
  return cap;
}

Distortion ParseDistortion(const std::string& name) {
  if (name == "radial-tangential" || name == "radtan") return Distortion::kRadialTangential;
  if (name == "equidistant" || name == "fisheye") return Distortion::kEquidistant;
  throw std::invalid_argument("CameraModel: unknown distortion_model '" + name +
                              "' (expected 'radial-tangential' or 'equidistant')");
}

}  // namespace

CameraModel::CameraModel(const CameraCalibration& calibration)
    : calibration_(calibration), distortion_(ParseDistortion(calibration.distortion_model)) {
  if (calibration.width <= 0 || calibration.height <= 0) {
    throw std::invalid_argument("CameraModel: image size must be positive, got " +
                                std::to_string(calibration.width) + "x" +
                                std::to_string(calibration.height));
  }
  if (!(calibration.intrinsics[0] > 0.0) || !(calibration.intrinsics[1] > 0.0)) {
    throw std::invalid_argument("CameraModel: focal lengths fu, fv must be positive");
  }
  const Eigen::Vector4d& k = calibration.distortion;
  if (distortion_ == Distortion::kRadialTangential) {
    // d/dr [r (1 + k1 r^2 + k2 r^4)] = 1 + 3 k1 r^2 + 5 k2 r^4
    max_valid_radius_ = FirstNonIncreasingRadius(
        [&k](double r) { return 1.0 + 3.0 * k[0] * r * r + 5.0 * k[1] * r * r * r * r; },
        kRadTanRadiusCap);
  } else {
    max_valid_radius_ = FirstNonIncreasingRadius(
        [this](double theta) {
          double d_thetad_d_theta = 0.0;
          DistortTheta(theta, &d_thetad_d_theta);
          return d_thetad_d_theta;
        },
        kEquidistantThetaCap);
  }
}

Eigen::Vector2d CameraModel::DistortRadTan(const Eigen::Vector2d& xy,
                                           Eigen::Matrix2d* d_xyd_d_xy) const {
  const Eigen::Vector4d& k = calibration_.distortion;
  const double x = xy.x(), y = xy.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + k[0] * r2 + k[1] * r2 * r2;
  const double p1 = k[2], p2 = k[3];
  Eigen::Vector2d xy_d(x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
                       y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y);
  if (d_xyd_d_xy != nullptr) {
    const double d_radial_d_r2 = k[0] + 2.0 * k[1] * r2;
    // d r2 / dx = 2x, d r2 / dy = 2y
    (*d_xyd_d_xy)(0, 0) = radial + 2.0 * x * x * d_radial_d_r2 + 2.0 * p1 * y + 6.0 * p2 * x;
    (*d_xyd_d_xy)(0, 1) = 2.0 * x * y * d_radial_d_r2 + 2.0 * p1 * x + 2.0 * p2 * y;
    (*d_xyd_d_xy)(1, 0) = 2.0 * x * y * d_radial_d_r2 + 2.0 * p1 * x + 2.0 * p2 * y;
    (*d_xyd_d_xy)(1, 1) = radial + 2.0 * y * y * d_radial_d_r2 + 6.0 * p1 * y + 2.0 * p2 * x;
  }
  return xy_d;
}

double CameraModel::DistortTheta(double theta, double* d_thetad_d_theta) const {
  const Eigen::Vector4d& k = calibration_.distortion;
  const double t2 = theta * theta;
  const double poly = 1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])));
  if (d_thetad_d_theta != nullptr) {
    *d_thetad_d_theta = 1.0 + t2 * (3.0 * k[0] + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])));
  }
  return theta * poly;
}

Eigen::Vector2d CameraModel::ToPixel(const Eigen::Vector2d& xy_d) const {
  const Eigen::Vector4d& in = calibration_.intrinsics;
  return Eigen::Vector2d(in[0] * xy_d.x() + in[2], in[1] * xy_d.y() + in[3]);
}

bool CameraModel::InImage(const Eigen::Vector2d& uv_px, double border_px) const {
  return uv_px.x() >= border_px && uv_px.y() >= border_px &&
         uv_px.x() <= calibration_.width - 1 - border_px &&
         uv_px.y() <= calibration_.height - 1 - border_px;
}

std::optional<Eigen::Vector2d> CameraModel::ProjectUnbounded(const Eigen::Vector3d& p_c) const {
  if (distortion_ == Distortion::kRadialTangential) {
    if (!(p_c.z() > 0.0)) return std::nullopt;
    const Eigen::Vector2d xy = p_c.head<2>() / p_c.z();
    if (xy.squaredNorm() > max_valid_radius_ * max_valid_radius_) return std::nullopt;
    return ToPixel(DistortRadTan(xy, nullptr));
  }
  const double rho = p_c.head<2>().norm();
  const double theta = std::atan2(rho, p_c.z());
  if (theta > max_valid_radius_) return std::nullopt;
  if (rho <= 1e-12 * p_c.norm()) {  // on the optical axis: theta_d / rho -> 1 / Z
    if (!(p_c.z() > 0.0)) return std::nullopt;
    return ToPixel(p_c.head<2>() / p_c.z());
  }
  return ToPixel(DistortTheta(theta, nullptr) / rho * p_c.head<2>());
}

std::optional<Eigen::Vector2d> CameraModel::Project(const Eigen::Vector3d& p_c) const {
  std::optional<Eigen::Vector2d> uv = ProjectUnbounded(p_c);
  if (!uv || !InImage(*uv)) return std::nullopt;
  return uv;
}

std::optional<Eigen::Vector3d> CameraModel::UndistortRadTan(const Eigen::Vector2d& xy_d) const {
  // Newton on F(xy) = distort(xy) - xy_d, starting at xy_d.
  Eigen::Vector2d xy = xy_d;
  for (int i = 0; i < kMaxNewtonIterations; ++i) {
    Eigen::Matrix2d d_xyd_d_xy;
    const Eigen::Vector2d residual = DistortRadTan(xy, &d_xyd_d_xy) - xy_d;
    if (residual.norm() < kNewtonTolerance) {
      if (xy.norm() > max_valid_radius_) return std::nullopt;
      return Eigen::Vector3d(xy.x(), xy.y(), 1.0).normalized();
    }
    xy -= d_xyd_d_xy.partialPivLu().solve(residual);
    if (!xy.allFinite()) return std::nullopt;
  }
  return std::nullopt;
}

std::optional<Eigen::Vector3d> CameraModel::UndistortEquidistant(const Eigen::Vector2d& xy_d) const {
  const double theta_d = xy_d.norm();
  if (theta_d < 1e-15) return Eigen::Vector3d::UnitZ();
  // Newton on theta_d(theta) = theta_d, starting at theta = theta_d.
  double theta = std::min(theta_d, max_valid_radius_);
  for (int i = 0; i < kMaxNewtonIterations; ++i) {
    double d_thetad_d_theta = 0.0;
    const double residual = DistortTheta(theta, &d_thetad_d_theta) - theta_d;
    if (std::abs(residual) < kNewtonTolerance) {
      const Eigen::Vector2d direction = xy_d / theta_d;
      return Eigen::Vector3d(std::sin(theta) * direction.x(), std::sin(theta) * direction.y(),
                             std::cos(theta));
    }
    if (!(d_thetad_d_theta > 0.0)) return std::nullopt;
    theta = std::clamp(theta - residual / d_thetad_d_theta, 0.0, max_valid_radius_);
  }
  return std::nullopt;
}

std::optional<Eigen::Vector3d> CameraModel::Unproject(const Eigen::Vector2d& uv_px) const {
  const Eigen::Vector4d& in = calibration_.intrinsics;
  const Eigen::Vector2d xy_d((uv_px.x() - in[2]) / in[0], (uv_px.y() - in[3]) / in[1]);
  return distortion_ == Distortion::kRadialTangential ? UndistortRadTan(xy_d)
                                                      : UndistortEquidistant(xy_d);
}

std::optional<Eigen::Vector2d> CameraModel::UnprojectToNormalized(const Eigen::Vector2d& uv_px) const {
  const std::optional<Eigen::Vector3d> bearing = Unproject(uv_px);
  if (!bearing || !(bearing->z() > 0.0)) return std::nullopt;
  return Eigen::Vector2d(bearing->x() / bearing->z(), bearing->y() / bearing->z());
}

}  // namespace vio::frontend
