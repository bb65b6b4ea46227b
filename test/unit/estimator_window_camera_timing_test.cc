// Window::ReleaseImageVelocities (batch frees the image velocities once a
// state's observations are added): the observations' factors keep their own,
// so the cost with the time offset away from the applied one is unchanged to
// the last bit, and it is not the cost without the velocities.
#include <map>

#include <gtest/gtest.h>

#include "vio/estimator/stereo_factor.h"
#include "vio/estimator/window.h"

namespace vio {
namespace {

const LandmarkId kLandmarks[] = {LandmarkId(1), LandmarkId(2)};

// Two states seeing two landmarks with image velocities of 300 px/s, the offset 4 ms from the
// applied one; released: the velocities dropped after the observations were added.
double Cost(bool released, double velocity_px_s = 300.0) {
  const ModelOptions model;
  const RectifiedStereo stereo;
  Window window(model, stereo);
  window.EstimateTimeOffset(0.0, 0.005);
  window.SetTimeOffset(0.004);
  const Eigen::Vector3d points[] = {{0.3, -0.2, 4.0}, {-0.5, 0.4, 6.0}};
  for (int k = 0; k < 2; ++k) window.AddLandmark(kLandmarks[k], points[k]);
  for (int i = 0; i < 2; ++i) {
    const StateId id(i);
    State& s = window.AddState(id, 50'000'000LL * i);
    s.SetPose(Eigen::Vector3d(0.05 * i, 0, 0), Eigen::Quaterniond::Identity());
    std::map<LandmarkId, Eigen::Vector3d> velocity;
    for (LandmarkId landmark : kLandmarks) velocity[landmark] = Eigen::Vector3d(velocity_px_s, velocity_px_s, -velocity_px_s);
    window.SetCameraTiming(id, 0.0, velocity);
    for (int k = 0; k < 2; ++k) {
      Eigen::Vector3d z_px;
      EXPECT_TRUE(StereoFactor::Project(stereo, s.p_w_b(), s.q_w_b(), points[k], &z_px));
      window.AddObservation(id, kLandmarks[k], z_px);
    }
    if (released) window.ReleaseImageVelocities(id);
  }
  double cost = 0;
  EXPECT_TRUE(window.problem().Evaluate(ceres::Problem::EvaluateOptions(), &cost, nullptr, nullptr, nullptr));
  return cost;
}

TEST(WindowCameraTiming, ReleasedVelocitiesLeaveTheCostUnchanged) {
  const double kept = Cost(false);
  EXPECT_EQ(Cost(true), kept);
  EXPECT_GT(std::abs(kept - Cost(false, 0.0)), 1e-3 * kept);  // the velocities matter
}

}  // namespace
}  // namespace vio
