// The simulated camera sensor: noise as the flags say, vignetting, auto
// exposure, motion blur that grows with angular rate and exposure time, and
// determinism per seed.
#include <cmath>
#include <optional>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "vio/simulator/render.h"
#include "vio/simulator/sensor.h"
#include "vio/simulator/simulator.h"

namespace vio::tools {
namespace {

cv::Mat Flat(float grey) { return cv::Mat(400, 500, CV_32FC1, cv::Scalar(grey)); }

void ExpectNoise(float grey, const SensorOptions& sensor) {
  cv::Mat image;
  ExposeImage(Flat(grey), 1.0, cv::Mat(), sensor, 5, &image);
  cv::Scalar mean, stddev;
  cv::meanStdDev(image, mean, stddev);
  const double expected = std::sqrt(sensor.read_noise * sensor.read_noise +
                                    sensor.shot_noise * sensor.shot_noise * grey / 128.0);
  EXPECT_NEAR(mean[0], grey, 0.05) << grey;
  EXPECT_NEAR(stddev[0], expected, 0.03 * expected) << grey;  // 200,000 pixels: sampling error < 0.5 %
}

TEST(SimulatorSensorTest, NoiseStandardDeviationMatchesTheOptions) {
  SensorOptions sensor;
  sensor.read_noise = 2.0;
  sensor.shot_noise = 3.0;
  ExpectNoise(128.0f, sensor);  // sqrt(4 + 9)
  ExpectNoise(32.0f, sensor);   // sqrt(4 + 9 / 4): shot noise falls with the signal
  sensor.shot_noise = 0.0;
  ExpectNoise(200.0f, sensor);
  sensor.read_noise = 0.0;
  cv::Mat image;
  ExposeImage(Flat(100.2f), 1.0, cv::Mat(), sensor, 5, &image);
  EXPECT_EQ(cv::countNonZero(image != 100), 0);  // no noise: rounding only
}

TEST(SimulatorSensorTest, NoiseIsAFunctionOfTheKey) {
  const SensorOptions sensor;
  cv::Mat a, b, c;
  ExposeImage(Flat(90.0f), 1.0, cv::Mat(), sensor, 11, &a);
  ExposeImage(Flat(90.0f), 1.0, cv::Mat(), sensor, 11, &b);
  ExposeImage(Flat(90.0f), 1.0, cv::Mat(), sensor, 12, &c);
  EXPECT_EQ(cv::countNonZero(a != b), 0);
  EXPECT_GT(cv::countNonZero(a != c), a.total() / 2);
}

TEST(SimulatorSensorTest, VignettingDarkensTowardsTheCorners) {
  const CameraCalibration camera = EurocStereoCalibration()[0];
  const cv::Mat map = VignettingMap(camera, 0.3);
  const int cu = static_cast<int>(std::lround(camera.intrinsics[2]));
  const int cv_ = static_cast<int>(std::lround(camera.intrinsics[3]));
  EXPECT_NEAR(map.at<float>(cv_, cu), 1.0f, 1e-4f);
  double lowest = 1.0;
  cv::minMaxLoc(map, &lowest);
  EXPECT_NEAR(lowest, 0.7, 1e-3);  // at the farthest corner
  EXPECT_LT(map.at<float>(cv_, 0), map.at<float>(cv_, cu - 100));
  SensorOptions sensor;
  sensor.read_noise = sensor.shot_noise = 0.0;
  cv::Mat image;
  ExposeImage(cv::Mat(camera.height, camera.width, CV_32FC1, cv::Scalar(200.0f)), 1.0, map, sensor, 1, &image);
  EXPECT_EQ(image.at<std::uint8_t>(cv_, cu), 200);
  EXPECT_NEAR(image.at<std::uint8_t>(0, camera.width - 1), 200 * map.at<float>(0, camera.width - 1), 0.5);
}

TEST(SimulatorSensorTest, ExposureChangesSmoothlyWithinItsRangeAndPerSeed) {
  SensorOptions sensor;
  sensor.exposure_variation = 0.3;
  double low = 10.0, high = 0.0, largest_step = 0.0;
  for (int k = 0; k < 2000; ++k) {  // 100 s at 20 Hz
    const double factor = ExposureFactor(sensor, 7, 0.05 * k);
    low = std::min(low, factor);
    high = std::max(high, factor);
    if (k > 0) largest_step = std::max(largest_step, std::abs(std::log(factor / ExposureFactor(sensor, 7, 0.05 * (k - 1)))));
    EXPECT_EQ(factor, ExposureFactor(sensor, 7, 0.05 * k));
  }
  EXPECT_GE(low, std::exp(-0.3) - 1e-12);
  EXPECT_LE(high, std::exp(0.3) + 1e-12);
  EXPECT_GT(high / low, std::exp(0.4));  // it does change
  EXPECT_LT(largest_step, 0.05);         // by less than 5 % from frame to frame
  EXPECT_NE(ExposureFactor(sensor, 7, 1.0), ExposureFactor(sensor, 8, 1.0));
  sensor.exposure_variation = 0.0;
  EXPECT_EQ(ExposureFactor(sensor, 7, 3.0), 1.0);
}

TEST(SimulatorSensorTest, OptionsOutOfRangeAreNamed) {
  SensorOptions sensor;
  sensor.vignetting = 1.0;
  EXPECT_THROW(CheckSensorOptions(sensor), std::invalid_argument);
  sensor = SensorOptions();
  sensor.max_blur_samples = 0;
  try {
    CheckSensorOptions(sensor);
    ADD_FAILURE() << "max_blur_samples = 0 accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("max_blur_samples"), std::string::npos) << e.what();
  }
  sensor = SensorOptions();
  sensor.exposure_ms = -1.0;
  EXPECT_THROW(CheckSensorOptions(sensor), std::invalid_argument);
}

// A camera turning about its y axis at `rate` [rad/s] during an exposure of
// `exposure_s`, rendered with motion blur; returns the image's gradient energy.
class MotionBlur : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    SimulatorOptions options;
    options.duration_s = 12.0;
    options.camera_output = SimCameraOutput::kImages;
    Simulation sim = BuildSimulation(options);
    scene_ = new Scene(std::move(sim.scene));
    camera_ = sim.dataset.cameras[0];
    T_w_c_ = sim.frames.back().T_w_b * camera_.T_b_c;
  }
  static void TearDownTestSuite() { delete scene_; }

  std::vector<Eigen::Isometry3d> Poses(double rate, double exposure_s) const {
    auto pose_at = [rate](double offset_s) -> std::optional<Eigen::Isometry3d> {
      Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
      turn.linear() = Eigen::AngleAxisd(rate * offset_s, Eigen::Vector3d::UnitY()).toRotationMatrix();
      return T_w_c_ * turn;
    };
    return ExposurePoses(pose_at, exposure_s, camera_.intrinsics[0], SensorOptions());
  }

  double GradientEnergy(double rate, double exposure_s) const {
    RenderOptions options;
    const SceneRenderer renderer(*scene_, camera_, options);
    const std::vector<Eigen::Isometry3d> poses = Poses(rate, exposure_s);
    cv::Mat radiance;
    for (const Eigen::Isometry3d& T : poses) renderer.AddRadiance(T, 1.0f / poses.size(), &radiance);
    cv::Mat gx;
    cv::Sobel(radiance, gx, CV_32F, 1, 0);
    return cv::mean(gx.mul(gx))[0];
  }

  static Scene* scene_;
  static CameraCalibration camera_;
  static Eigen::Isometry3d T_w_c_;
};
Scene* MotionBlur::scene_ = nullptr;
CameraCalibration MotionBlur::camera_;
Eigen::Isometry3d MotionBlur::T_w_c_;

TEST_F(MotionBlur, SubFramesFollowTheImageMotion) {
  EXPECT_EQ(Poses(0.0, 0.01).size(), 1u);    // standing still: one render
  EXPECT_EQ(Poses(2.0, 0.0).size(), 1u);     // no exposure time: no blur
  EXPECT_EQ(Poses(0.02, 0.01).size(), 1u);   // 0.09 px of motion
  const std::size_t slow = Poses(0.5, 0.01).size(), fast = Poses(1.0, 0.01).size();
  EXPECT_GE(slow, 4u);   // 2.3 px over the exposure, <= 0.5 px apart
  EXPECT_GT(fast, slow);
  EXPECT_EQ(Poses(1.0, 0.02).size(), std::size_t{SensorOptions().max_blur_samples});  // capped
  // The sub-frames span the exposure symmetrically about the frame's pose.
  const std::vector<Eigen::Isometry3d> poses = Poses(1.0, 0.01);
  const Eigen::AngleAxisd first(T_w_c_.linear().transpose() * poses.front().linear());
  const Eigen::AngleAxisd last(T_w_c_.linear().transpose() * poses.back().linear());
  EXPECT_NEAR(first.angle(), last.angle(), 1e-9);
  EXPECT_NEAR(first.angle(), 0.005 * (1.0 - 1.0 / poses.size()), 1e-9);
}

TEST_F(MotionBlur, BlurGrowsWithAngularRateAndExposure) {
  const double still = GradientEnergy(0.0, 0.01);
  const double slow = GradientEnergy(1.0, 0.01);
  const double fast = GradientEnergy(2.0, 0.01);
  const double fast_long = GradientEnergy(2.0, 0.02);
  EXPECT_LT(slow, 0.8 * still);
  EXPECT_LT(fast, 0.9 * slow);
  EXPECT_LT(fast_long, 0.9 * fast);
}

}  // namespace
}  // namespace vio::tools
