#include "vio/frontend/stereo_rectifier.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <glog/logging.h>
#include <opencv2/calib3d.hpp>

namespace vio::frontend {
namespace {

cv::Matx33d CameraMatrix(const CameraCalibration& camera) {
  const Eigen::Vector4d& in = camera.intrinsics;
  return cv::Matx33d(in[0], 0.0, in[2], 0.0, in[1], in[3], 0.0, 0.0, 1.0);
}

cv::Vec4d DistortionCoefficients(const CameraCalibration& camera) {
  const Eigen::Vector4d& d = camera.distortion;
  return cv::Vec4d(d[0], d[1], d[2], d[3]);
}

cv::Matx33d ToCv(const Eigen::Matrix3d& m) {
  cv::Matx33d out;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out(r, c) = m(r, c);
  }
  return out;
}

cv::Mat ToCv(const Eigen::Matrix<double, 3, 4>& m) {
  cv::Mat out(3, 4, CV_64F);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 4; ++c) out.at<double>(r, c) = m(r, c);
  }
  return out;
}

template <int Rows, int Cols>
Eigen::Matrix<double, Rows, Cols> ToEigen(const cv::Mat& m) {
  CHECK_EQ(m.rows, Rows);
  CHECK_EQ(m.cols, Cols);
  cv::Mat m64;
  m.convertTo(m64, CV_64F);
  Eigen::Matrix<double, Rows, Cols> out;
  for (int r = 0; r < Rows; ++r) {
    for (int c = 0; c < Cols; ++c) out(r, c) = m64.at<double>(r, c);
  }
  return out;
}

void CheckPair(const CameraCalibration& cam0, const CameraCalibration& cam1) {
  if (cam0.distortion_model != cam1.distortion_model) {
    throw std::invalid_argument("StereoRectifier: cameras use different distortion models ('" +
                                cam0.distortion_model + "' vs '" + cam1.distortion_model + "')");
  }
  if (cam0.width != cam1.width || cam0.height != cam1.height) {
    throw std::invalid_argument("StereoRectifier: cameras have different image sizes");
  }
  const Eigen::Vector3d p_c0_c1 = (cam0.T_b_c.inverse() * cam1.T_b_c).translation();
  if (!(p_c0_c1.x() > 0.0) || p_c0_c1.x() < 2.0 * p_c0_c1.tail<2>().norm()) {
    throw std::invalid_argument(
        "StereoRectifier: cam1 must sit to the right of cam0 (along cam0's +x axis); its "
        "position in cam0 is (" +
        std::to_string(p_c0_c1.x()) + ", " + std::to_string(p_c0_c1.y()) + ", " +
        std::to_string(p_c0_c1.z()) + ") m");
  }
}

}  // namespace

StereoRectifier::StereoRectifier(const CameraCalibration& cam0, const CameraCalibration& cam1)
    : models_{CameraModel(cam0), CameraModel(cam1)} {
  CheckPair(cam0, cam1);
  ComputeRectification();
}

std::size_t StereoRectifier::Index(int camera) {
  CHECK(camera == 0 || camera == 1) << "camera index must be 0 or 1, got " << camera;
  return static_cast<std::size_t>(camera);
}

void StereoRectifier::ComputeRectification() {
  const CameraCalibration& cam0 = models_[0].calibration();
  const CameraCalibration& cam1 = models_[1].calibration();
  // p_c1 = R * p_c0 + T (OpenCV's convention for the pair).
  const Eigen::Isometry3d T_c1_c0 = cam1.T_b_c.inverse() * cam0.T_b_c;
  const cv::Matx33d R = ToCv(Eigen::Matrix3d(T_c1_c0.rotation()));
  const cv::Vec3d T(T_c1_c0.translation().x(), T_c1_c0.translation().y(),
                    T_c1_c0.translation().z());
  const cv::Size size(cam0.width, cam0.height);
  cv::Mat R1, R2, P1, P2, Q;
  if (models_[0].distortion() == CameraModel::Distortion::kRadialTangential) {
    cv::stereoRectify(CameraMatrix(cam0), DistortionCoefficients(cam0), CameraMatrix(cam1),
                      DistortionCoefficients(cam1), size, R, T, R1, R2, P1, P2, Q,
                      cv::CALIB_ZERO_DISPARITY, /*alpha=*/0.0, size);
  } else {
    cv::fisheye::stereoRectify(CameraMatrix(cam0), DistortionCoefficients(cam0), CameraMatrix(cam1),
                               DistortionCoefficients(cam1), size, R, T, R1, R2, P1, P2, Q,
                               cv::CALIB_ZERO_DISPARITY, size, /*balance=*/0.0);
  }
  R_rect_cam_ = {ToEigen<3, 3>(R1), ToEigen<3, 3>(R2)};
  P_ = {ToEigen<3, 4>(P1), ToEigen<3, 4>(P2)};
  rectified_.f = P_[0](0, 0);
  rectified_.cx = P_[0](0, 2);
  rectified_.cy = P_[0](1, 2);
  rectified_.baseline = -P_[1](0, 3) / P_[1](0, 0);
  rectified_.T_b_cl = cam0.T_b_c;
  rectified_.T_b_cl.linear() = cam0.T_b_c.rotation() * R_rect_cam_[0].transpose();
  if (!(rectified_.baseline > 0.0)) {
    throw std::invalid_argument("the calibration puts cam1 left of cam0 (rectified baseline " +
                                std::to_string(rectified_.baseline) + " m): cam0 must be the left camera; are cam0 "
                                "and cam1 swapped in the calibration (T_BS of cam0/cam1 sensor.yaml)?");
  }
  CHECK_NEAR(P_[0](1, 1), rectified_.f, 1e-9 * rectified_.f);
  CHECK_LT(std::abs(P_[1](0, 2) - rectified_.cx), 1e-9 * rectified_.f)
      << "expected CALIB_ZERO_DISPARITY";
}

std::optional<Eigen::Vector2d> StereoRectifier::Rectify(int camera, const Eigen::Vector2d& uv_px) const {
  const std::size_t k = Index(camera);
  const std::optional<Eigen::Vector3d> bearing = models_[k].Unproject(uv_px);
  if (!bearing) return std::nullopt;
  const Eigen::Vector3d p_rect = R_rect_cam_[k] * *bearing;
  if (!(p_rect.z() > 0.0)) return std::nullopt;
  const Eigen::Matrix<double, 3, 4>& P = P_[k];
  return Eigen::Vector2d(P(0, 0) * p_rect.x() / p_rect.z() + P(0, 2),
                         P(1, 1) * p_rect.y() / p_rect.z() + P(1, 2));
}

std::optional<Eigen::Vector3d> StereoRectifier::RectifyStereo(const Eigen::Vector2d& uv0_px,
                                                              const Eigen::Vector2d& uv1_px) const {
  const std::optional<Eigen::Vector2d> left = Rectify(0, uv0_px);
  const std::optional<Eigen::Vector2d> right = Rectify(1, uv1_px);
  if (!left || !right) return std::nullopt;
  return Eigen::Vector3d(left->x(), right->x(), 0.5 * (left->y() + right->y()));
}

std::vector<Eigen::Vector2d> StereoRectifier::RectifyWithOpenCv(
    int camera, const std::vector<Eigen::Vector2d>& uv_px) const {
  const std::size_t k = Index(camera);
  const CameraCalibration& cam = models_[k].calibration();
  std::vector<cv::Point2d> src, dst;
  for (const Eigen::Vector2d& uv : uv_px) src.emplace_back(uv.x(), uv.y());
  if (src.empty()) return {};
  const cv::Mat P = ToCv(P_[k]);
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 1000, 1e-14);
  if (models_[k].distortion() == CameraModel::Distortion::kRadialTangential) {
    cv::undistortPoints(src, dst, CameraMatrix(cam), DistortionCoefficients(cam),
                        ToCv(R_rect_cam_[k]), P, criteria);
  } else {
    cv::fisheye::undistortPoints(src, dst, CameraMatrix(cam), DistortionCoefficients(cam),
                                 ToCv(R_rect_cam_[k]), P, criteria);
  }
  std::vector<Eigen::Vector2d> out;
  out.reserve(dst.size());
  for (const cv::Point2d& p : dst) out.emplace_back(p.x, p.y);
  return out;
}

std::pair<cv::Mat, cv::Mat> StereoRectifier::RectificationMaps(int camera) const {
  const std::size_t k = Index(camera);
  const CameraCalibration& cam = models_[k].calibration();
  const cv::Mat P = ToCv(P_[k]);
  const cv::Size size(cam.width, cam.height);
  cv::Mat map_x, map_y;
  if (models_[k].distortion() == CameraModel::Distortion::kRadialTangential) {
    cv::initUndistortRectifyMap(CameraMatrix(cam), DistortionCoefficients(cam), ToCv(R_rect_cam_[k]),
                                P, size, CV_32FC1, map_x, map_y);
  } else {
    cv::fisheye::initUndistortRectifyMap(CameraMatrix(cam), DistortionCoefficients(cam),
                                         ToCv(R_rect_cam_[k]), P, size, CV_32FC1, map_x, map_y);
  }
  return {map_x, map_y};
}

}  // namespace vio::frontend
