// Window::SetCameraTiming: a state's applied offset t_a and camera motion reach its observations'
// factors: the window's cost, with the offset 4 ms from t_a, is that of StereoCalibrationFactors
// made with them (to 1e-12), and the motion matters.
#include <gtest/gtest.h>

#include "vio/estimator/stereo_calibration_factor.h"
#include "vio/estimator/stereo_factor.h"
#include "vio/estimator/window.h"

namespace vio {
namespace {

const LandmarkId kLandmarks[] = {LandmarkId(1), LandmarkId(2)};
const Eigen::Vector3d kPoints[] = {{0.3, -0.2, 4.0}, {-0.5, 0.4, 6.0}};

CameraMotion Motion(double scale) {
  CameraMotion motion;
  motion.omega_c = scale * Eigen::Vector3d(0.3, -0.5, 0.2);
  motion.v_c = scale * Eigen::Vector3d(0.8, 0.1, -0.4);
  return motion;
}

// Two states seeing two landmarks (observed 0.5 px off their projections), the offset 4 ms from
// the applied one (1 ms); direct: the same factors evaluated outside the window.
double Cost(double motion_scale, bool direct) {
  ModelOptions model;
  model.huber_px = 0;
  const RectifiedStereo stereo;
  Window window(model, stereo);
  window.EstimateTimeOffset(0.0, 0.005);
  window.SetTimeOffset(0.005);
  for (int k = 0; k < 2; ++k) window.AddLandmark(kLandmarks[k], kPoints[k]);
  double cost = 0;
  for (int i = 0; i < 2; ++i) {
    const StateId id(i);
    State& s = window.AddState(id, 50'000'000LL * i);
    s.SetPose(Eigen::Vector3d(0.05 * i, 0, 0), Eigen::Quaterniond::Identity());
    const StereoCalibrationFactor::TimeOffset timing{Motion(motion_scale), 0.001};
    window.SetCameraTiming(id, timing.applied_offset_s, timing.motion);
    for (int k = 0; k < 2; ++k) {
      Eigen::Vector3d z_px;
      EXPECT_TRUE(StereoFactor::Project(stereo, s.p_w_b(), s.q_w_b(), kPoints[k], &z_px));
      z_px += Eigen::Vector3d(0.5, 0.5, -0.5);
      window.AddObservation(id, kLandmarks[k], z_px);
      const StereoCalibrationFactor factor(z_px, stereo, model.pixel_sigma, &timing, false);
      const double td = 0.005;
      const double* parameters[3] = {s.pose, kPoints[k].data(), &td};
      Eigen::Vector3d r;
      EXPECT_TRUE(factor.Evaluate(parameters, r.data(), nullptr));
      cost += 0.5 * r.squaredNorm();
    }
  }
  if (direct) return cost;
  cost = 0;
  EXPECT_TRUE(window.problem().Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, nullptr));
  return cost - 0.5 * (0.005 / 0.005) * (0.005 / 0.005);  // without the offset's prior (1 sigma)
}

TEST(WindowCameraTiming, TheStatesMotionAndAppliedOffsetReachItsFactors) {
  const double cost = Cost(1.0, false);
  EXPECT_NEAR(cost, Cost(1.0, true), 1e-12 * cost);
  EXPECT_GT(std::abs(cost - Cost(0.0, false)), 1e-3 * cost);  // the motion matters
}

}  // namespace
}  // namespace vio
