// A landmark a failed Gauss-Newton step drops must leave every structure that refers to it.
//
// Window::Solve undoes a step whose end point does not evaluate, drops the observations that fail
// there and a landmark they leave unobserved (Window::DropOutlierObservations). The MSCKF holds the
// ids of the landmarks it added for the update (to marginalize them after the solve), of retired
// long-lived landmarks, and its long-lived set; each must forget a dropped landmark. Scripted here:
// during one frame's update every stereo factor the window creates fails to evaluate anywhere but at
// the point it was first evaluated at, so the update's step is rejected and the landmarks added in
// that frame are dropped. Before the fix the MSCKF then aborted in Window::Marginalize ("no landmark
// N in the window"), and a dropped long-lived landmark stayed in its kept set.
#include <memory>
#include <set>
#include <vector>

#include <ceres/cost_function.h>
#include <gtest/gtest.h>

#include "synthetic_window.h"
#include "vio/estimator/msckf_policy.h"
#include "vio/estimator/window.h"

namespace vio {
namespace {

constexpr int kFirst = 60;
constexpr int kFrames = 24;
constexpr int kFailingFrame = 8;

const test::SyntheticFlight& Flight() {
  static const test::SyntheticFlight flight(6.0, 11);
  return flight;
}

// A stereo factor (sizes 3 x {7, 3}) that evaluates only at the parameter values of its first
// evaluation: any step moving its landmark or pose ends where it does not evaluate. Other factors
// pass through.
class FailsWhenMoved final : public ceres::CostFunction {
 public:
  explicit FailsWhenMoved(ceres::CostFunction* factor) : factor_(factor) {
    set_num_residuals(factor->num_residuals());
    *mutable_parameter_block_sizes() = factor->parameter_block_sizes();
  }
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override {
    if (IsStereo()) {
      std::vector<double> values(parameters[0], parameters[0] + 7);
      values.insert(values.end(), parameters[1], parameters[1] + 3);
      if (first_.empty()) first_ = values;
      if (values != first_) return false;
    }
    return factor_->Evaluate(parameters, residuals, jacobians);
  }

 private:
  bool IsStereo() const {
    const std::vector<int32_t>& sizes = parameter_block_sizes();
    return num_residuals() == 3 && sizes.size() == 2 && sizes[0] == 7 && sizes[1] == 3;
  }
  std::unique_ptr<ceres::CostFunction> factor_;
  mutable std::vector<double> first_;
};

EstimatorOptions Options(int persistent_landmarks) {
  EstimatorOptions options;
  options.policy.policy = "msckf";
  options.policy.window_size = 5;
  options.solver.step = "gn";
  options.persistent.persistent_landmarks = persistent_landmarks;
  options.persistent.persistent_min_track = 3;
  options.persistent.persistent_retire_s = 0.2;
  return options;
}

struct ScriptResult {
  std::set<LandmarkId> dropped;  ///< in the failing frame
  int rejected_steps = 0;
  int frames = 0;                ///< frames updated
};

ScriptResult RunWithAFailingFrame(const EstimatorOptions& options) {
  Window window(options.model, Flight().stereo());
  MsckfPolicy policy(options, options.msckf.msckf_gn_steps);
  ScriptResult result;
  for (int k = 0; k < kFrames; ++k) {
    Flight().AddState(window, kFirst, k, Eigen::Vector3d::Zero());
    window.ClearRemovals();
    if (k == kFailingFrame) {
      window.SetFactorWrapper([](ceres::CostFunction* factor) { return new FailsWhenMoved(factor); });
    }
    policy.Update(Flight().frames()[kFirst + k], StateId(k), window);
    window.SetFactorWrapper({});
    if (k == kFailingFrame) {
      result.dropped.insert(window.removals().dropped_landmarks.begin(), window.removals().dropped_landmarks.end());
      result.rejected_steps = window.health().rejected_steps;
    }
    for (LandmarkId id : result.dropped) {
      EXPECT_FALSE(policy.persistent().IsKept(id) && !window.HasLandmark(id))
          << "frame " << k << ": landmark " << id.value << " is kept but not in the window";
    }
    ++result.frames;
  }
  return result;
}

TEST(DroppedLandmark, TheMsckfForgetsTheLandmarksAFailedStepDropped) {
  const ScriptResult result = RunWithAFailingFrame(Options(0));
  EXPECT_GE(result.rejected_steps, 1);
  EXPECT_FALSE(result.dropped.empty()) << "the failing frame should drop the landmarks it added";
  EXPECT_EQ(result.frames, kFrames);
}

TEST(DroppedLandmark, LongLivedLandmarksForgetADroppedOne) {
  const ScriptResult result = RunWithAFailingFrame(Options(20));
  EXPECT_GE(result.rejected_steps, 1);
  EXPECT_FALSE(result.dropped.empty());
  EXPECT_EQ(result.frames, kFrames);
}

}  // namespace
}  // namespace vio
