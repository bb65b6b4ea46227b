// CameraModel (radial-tangential and equidistant) and StereoRectifier, on the
// real EuRoC V2_01 calibration.
#include <random>
#include <stdexcept>
#include <vector>

#include <gtest/gtest.h>

#include "euroc_calibration.h"
#include "vio/frontend/camera_model.h"
#include "vio/frontend/stereo_rectifier.h"

namespace vio::frontend {
namespace {

CameraCalibration EurocCam0() { return test::EurocCamera(0); }
CameraCalibration EurocCam1() { return test::EurocCamera(1); }

CameraCalibration AsEquidistant(CameraCalibration cam) {
  cam.distortion_model = "equidistant";
  return cam;
}

// Every pixel of a grid over the whole image (borders included) unprojects and
// projects back to itself.
void ExpectPixelRoundTrip(const CameraModel& model) {
  double worst_px = 0.0;
  for (int v = 0; v < model.height(); v += 6) {
    for (int u = 0; u < model.width(); u += 6) {
      for (const Eigen::Vector2d& uv : {Eigen::Vector2d(u, v), Eigen::Vector2d(model.width() - 1, v),
                                       Eigen::Vector2d(u, model.height() - 1)}) {
        const std::optional<Eigen::Vector3d> bearing = model.Unproject(uv);
        ASSERT_TRUE(bearing.has_value()) << "pixel " << uv.transpose();
        EXPECT_NEAR(bearing->norm(), 1.0, 1e-12);
        const std::optional<Eigen::Vector2d> back = model.ProjectUnbounded(*bearing * 3.7);
        ASSERT_TRUE(back.has_value()) << "pixel " << uv.transpose();
        worst_px = std::max(worst_px, (*back - uv).norm());
      }
    }
  }
  EXPECT_LT(worst_px, 1e-6);
}

TEST(CameraModelTest, RadialTangentialPixelRoundTripOverWholeImage) {
  ExpectPixelRoundTrip(CameraModel(EurocCam0()));
  ExpectPixelRoundTrip(CameraModel(EurocCam1()));
}

TEST(CameraModelTest, EquidistantPixelRoundTripOverWholeImage) {
  ExpectPixelRoundTrip(CameraModel(AsEquidistant(EurocCam0())));
  CameraCalibration fisheye = AsEquidistant(EurocCam0());  // TUM-VI-like fisheye lens
  fisheye.intrinsics = Eigen::Vector4d(190.98, 190.97, 254.93, 256.90);
  fisheye.distortion = Eigen::Vector4d(0.00348, 0.00072, -0.00205, 0.00020);
  fisheye.width = fisheye.height = 512;
  ExpectPixelRoundTrip(CameraModel(fisheye));
}

TEST(CameraModelTest, PointRoundTripKeepsBearing) {
  for (const CameraCalibration& cam : {EurocCam0(), AsEquidistant(EurocCam0())}) {
    const CameraModel model(cam);
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> lateral(-1.0, 1.0), depth(0.5, 10.0);
    int projected = 0;
    for (int i = 0; i < 2000; ++i) {
      const double z = depth(rng);
      const Eigen::Vector3d p_c(lateral(rng) * z, lateral(rng) * z * 0.7, z);
      const std::optional<Eigen::Vector2d> uv = model.Project(p_c);
      if (!uv) continue;
      ++projected;
      const std::optional<Eigen::Vector3d> bearing = model.Unproject(*uv);
      ASSERT_TRUE(bearing.has_value());
      EXPECT_LT((*bearing - p_c.normalized()).norm(), 1e-10);
    }
    EXPECT_GT(projected, 500);
  }
}

TEST(CameraModelTest, RejectsPointsBehindOrOutsideTheImage) {
  const CameraModel model(EurocCam0());
  EXPECT_FALSE(model.Project(Eigen::Vector3d(0.1, 0.1, -1.0)).has_value());
  EXPECT_FALSE(model.Project(Eigen::Vector3d(0.0, 0.0, 0.0)).has_value());
  EXPECT_FALSE(model.Project(Eigen::Vector3d(5.0, 0.0, 1.0)).has_value());  // ~79 deg off axis
  EXPECT_TRUE(model.Project(Eigen::Vector3d(0.0, 0.0, 1.0)).has_value());
  const std::optional<Eigen::Vector2d> centre = model.Project(Eigen::Vector3d(0.0, 0.0, 2.0));
  ASSERT_TRUE(centre.has_value());
  EXPECT_NEAR(centre->x(), 367.215, 1e-12);
  EXPECT_NEAR(centre->y(), 248.375, 1e-12);
}

TEST(CameraModelTest, FoldingDistortionHasBoundedValidRadius) {
  CameraCalibration cam = EurocCam0();
  cam.distortion = Eigen::Vector4d(-0.5, 0.0, 0.0, 0.0);  // r (1 - 0.5 r^2) peaks at r = sqrt(2/3)
  const CameraModel model(cam);
  EXPECT_NEAR(model.max_valid_radius(), std::sqrt(2.0 / 3.0), 2e-3);
  EXPECT_FALSE(model.ProjectUnbounded(Eigen::Vector3d(1.5, 0.0, 1.0)).has_value());
  EXPECT_TRUE(model.ProjectUnbounded(Eigen::Vector3d(0.7, 0.0, 1.0)).has_value());
}

TEST(CameraModelTest, RejectsBadCalibration) {
  CameraCalibration cam = EurocCam0();
  cam.distortion_model = "omni";
  EXPECT_THROW(CameraModel{cam}, std::invalid_argument);
  cam = EurocCam0();
  cam.intrinsics[0] = 0.0;
  EXPECT_THROW(CameraModel{cam}, std::invalid_argument);
  EXPECT_THROW(StereoRectifier(EurocCam1(), EurocCam0()), std::invalid_argument);  // swapped
}

// A point projected through the real distorted cameras and rectified equals
// its projection with the RectifiedStereo pinhole pair.
TEST(StereoRectifierTest, RectifiedPixelsMatchRectifiedPinholeProjection) {
  const StereoRectifier rectifier(EurocCam0(), EurocCam1());
  const RectifiedStereo& rect = rectifier.rectified();
  EXPECT_NEAR(rect.baseline, 0.110, 0.002);
  EXPECT_LT((rect.T_b_cl.translation() - EurocCam0().T_b_c.translation()).norm(), 1e-12);
  const CameraModel cam0(EurocCam0()), cam1(EurocCam1());
  const Eigen::Isometry3d T_c1_c0 = EurocCam1().T_b_c.inverse() * EurocCam0().T_b_c;
  const Eigen::Isometry3d T_cl_c0 = rect.T_b_cl.inverse() * EurocCam0().T_b_c;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> lateral(-0.9, 0.9), depth(0.8, 12.0);
  int checked = 0;
  for (int i = 0; i < 3000; ++i) {
    const double z = depth(rng);
    const Eigen::Vector3d p_c0(lateral(rng) * z, lateral(rng) * z * 0.6, z);
    const auto uv0 = cam0.Project(p_c0);
    const auto uv1 = cam1.Project(T_c1_c0 * p_c0);
    if (!uv0 || !uv1) continue;
    const auto left = rectifier.Rectify(0, *uv0);
    const auto right = rectifier.Rectify(1, *uv1);
    ASSERT_TRUE(left && right);
    const Eigen::Vector3d p_cl = T_cl_c0 * p_c0;
    const double u_l = rect.f * p_cl.x() / p_cl.z() + rect.cx;
    const double u_r = rect.f * (p_cl.x() - rect.baseline) / p_cl.z() + rect.cx;
    const double v = rect.f * p_cl.y() / p_cl.z() + rect.cy;
    EXPECT_NEAR(left->x(), u_l, 1e-3);
    EXPECT_NEAR(right->x(), u_r, 1e-3);
    EXPECT_NEAR(left->y(), v, 1e-3);
    EXPECT_NEAR(right->y(), left->y(), 1e-3);  // rows are epipolar lines
    const auto z_px = rectifier.RectifyStereo(*uv0, *uv1);
    ASSERT_TRUE(z_px.has_value());
    EXPECT_NEAR(z_px->z(), v, 1e-3);
    ++checked;
  }
  EXPECT_GT(checked, 1000);
}

TEST(StereoRectifierTest, OwnModelAgreesWithOpenCvUndistortPoints) {
  const StereoRectifier rectifier(EurocCam0(), EurocCam1());
  for (int camera : {0, 1}) {
    std::vector<Eigen::Vector2d> pixels;
    for (int v = 0; v < 480; v += 20) {
      for (int u = 0; u < 752; u += 20) pixels.emplace_back(u, v);
    }
    const std::vector<Eigen::Vector2d> cv_rect = rectifier.RectifyWithOpenCv(camera, pixels);
    ASSERT_EQ(cv_rect.size(), pixels.size());
    for (std::size_t i = 0; i < pixels.size(); ++i) {
      const auto own = rectifier.Rectify(camera, pixels[i]);
      ASSERT_TRUE(own.has_value());
      EXPECT_NEAR((*own - cv_rect[i]).norm(), 0.0, 1e-5) << "camera " << camera << " pixel "
                                                         << pixels[i].transpose();
    }
  }
}

// alpha = 0: every pixel of the rectified image comes from inside the source image.
TEST(StereoRectifierTest, RectifiedImageHasNoInvalidPixels) {
  const StereoRectifier rectifier(EurocCam0(), EurocCam1());
  const RectifiedStereo& rect = rectifier.rectified();
  for (int camera : {0, 1}) {
    const CameraModel& model = rectifier.camera_model(camera);
    auto check = [&](double u, double v) {
      const Eigen::Vector3d p_rect((u - rect.cx) / rect.f, (v - rect.cy) / rect.f, 1.0);
      const auto uv = model.ProjectUnbounded(rectifier.R_rect_cam(camera).transpose() * p_rect);
      ASSERT_TRUE(uv.has_value());
      EXPECT_TRUE(model.InImage(*uv, -1.0)) << "rectified (" << u << ", " << v << ") -> "
                                            << uv->transpose();
    };
    for (int u = 0; u < 752; u += 4) {
      check(u, 0);
      check(u, 479);
    }
    for (int v = 0; v < 480; v += 4) {
      check(0, v);
      check(751, v);
    }
  }
}

TEST(StereoRectifierTest, RectificationMapsMatchRectify) {
  const StereoRectifier rectifier(EurocCam0(), EurocCam1());
  const auto [map_x, map_y] = rectifier.RectificationMaps(0);
  ASSERT_EQ(map_x.cols, 752);
  ASSERT_EQ(map_x.rows, 480);
  for (int v = 10; v < 480; v += 97) {
    for (int u = 10; u < 752; u += 101) {
      const Eigen::Vector2d source(map_x.at<float>(v, u), map_y.at<float>(v, u));
      const auto rectified = rectifier.Rectify(0, source);
      ASSERT_TRUE(rectified.has_value());
      EXPECT_NEAR(rectified->x(), u, 1e-2);
      EXPECT_NEAR(rectified->y(), v, 1e-2);
    }
  }
}

}  // namespace
}  // namespace vio::frontend
