// Simulated feature tracks on a short synthetic flight: observations are in
// the image, noise-free ones reproject exactly, noise and outliers have the
// requested statistics, tracks are long.
#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <tuple>

#include <gtest/gtest.h>

#include "vio/frontend/camera_model.h"
#include "vio/simulator/simulator.h"

namespace vio::tools {
namespace {

SimulatorOptions ShortFlight(double pixel_noise_px, double outlier_rate) {
  SimulatorOptions options;
  options.duration_s = 8.0;
  options.seed = 17;
  options.features.pixel_noise_px = pixel_noise_px;
  options.features.outlier_rate = outlier_rate;
  return options;
}

// The true pixel of every observation: the landmark projected from the
// ground-truth pose through the real camera model.
std::vector<Eigen::Vector2d> TruePixels(const Simulation& sim) {
  std::map<Timestamp, Eigen::Isometry3d> T_w_b;
  for (const FramePose& f : sim.frames) T_w_b[f.t_ns] = f.T_w_b;
  const frontend::CameraModel models[2] = {frontend::CameraModel(sim.dataset.cameras[0]),
                                           frontend::CameraModel(sim.dataset.cameras[1])};
  std::vector<Eigen::Vector2d> pixels;
  for (const FeatureObservation& obs : sim.dataset.features) {
    const Eigen::Isometry3d T_w_c = T_w_b.at(obs.t_ns) * sim.dataset.cameras[obs.camera].T_b_c;
    const Eigen::Vector3d p_c = T_w_c.inverse() * sim.scene.landmarks.at(obs.feature_id).p_w;
    const auto uv = models[obs.camera].Project(p_c);
    EXPECT_TRUE(uv.has_value());
    pixels.push_back(uv.value_or(Eigen::Vector2d::Constant(-1e9)));
  }
  return pixels;
}

TEST(SimulateFeaturesTest, NoiseFreeObservationsReprojectExactlyInsideTheImage) {
  const Simulation sim = BuildSimulation(ShortFlight(0.0, 0.0));
  ASSERT_EQ(sim.frames.size(), 161u);
  ASSERT_FALSE(sim.dataset.features.empty());
  const std::vector<Eigen::Vector2d> truth = TruePixels(sim);
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const FeatureObservation& obs = sim.dataset.features[i];
    EXPECT_LT((obs.uv_px - truth[i]).norm(), 1e-9);
    EXPECT_GE(obs.uv_px.minCoeff(), 0.0);
    EXPECT_LE(obs.uv_px.x(), sim.dataset.cameras[obs.camera].width - 1);
    EXPECT_LE(obs.uv_px.y(), sim.dataset.cameras[obs.camera].height - 1);
  }
}

TEST(SimulateFeaturesTest, FramesAreSortedBudgetedAndStereoIdsAreShared) {
  const Simulation sim = BuildSimulation(ShortFlight(0.5, 0.0));
  const auto& obs = sim.dataset.features;
  EXPECT_TRUE(std::is_sorted(obs.begin(), obs.end(), [](const auto& a, const auto& b) {
    return std::tie(a.t_ns, a.camera, a.feature_id) < std::tie(b.t_ns, b.camera, b.feature_id);
  }));
  std::map<Timestamp, std::set<std::int64_t>> ids[2];
  for (const FeatureObservation& o : obs) EXPECT_TRUE(ids[o.camera][o.t_ns].insert(o.feature_id).second);
  for (const auto& [t, right] : ids[1]) {
    const std::set<std::int64_t>& left = ids[0][t];
    EXPECT_TRUE(std::includes(left.begin(), left.end(), right.begin(), right.end()));
  }
  for (const auto& [t, left] : ids[0]) EXPECT_LE(static_cast<int>(left.size()), 150);
  ASSERT_EQ(sim.features.stereo_count.size(), sim.frames.size());
  double stereo = 0.0;
  for (int n : sim.features.stereo_count) stereo += n;
  EXPECT_GE(stereo / sim.frames.size(), 80.0);
  EXPECT_GE(MedianTrackLength(sim.features), 10.0);
}

TEST(SimulateFeaturesTest, PixelNoiseAndOutliersHaveTheRequestedRates) {
  const Simulation sim = BuildSimulation(ShortFlight(0.5, 0.1));
  const std::vector<Eigen::Vector2d> truth = TruePixels(sim);
  double sum_sq = 0.0;
  int inliers = 0, outliers = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const double error = (sim.dataset.features[i].uv_px - truth[i]).norm();
    if (error > 5.0) {
      ++outliers;
    } else {
      sum_sq += error * error;
      ++inliers;
    }
  }
  const double n = static_cast<double>(truth.size());
  EXPECT_NEAR(outliers / n, 0.1, 0.015);  // a few random pixels land close to the truth
  EXPECT_NEAR(std::sqrt(sum_sq / (2.0 * inliers)), 0.5, 0.02);
}

TEST(SimulateFeaturesTest, RejectsBadOptions) {
  SimulatorOptions options = ShortFlight(0.5, 1.5);
  EXPECT_THROW(BuildSimulation(options), std::invalid_argument);
  options = ShortFlight(-1.0, 0.0);
  EXPECT_THROW(BuildSimulation(options), std::invalid_argument);
  options = ShortFlight(0.5, 0.0);
  options.features.max_features = 0;
  EXPECT_THROW(BuildSimulation(options), std::invalid_argument);
  options = ShortFlight(0.5, 0.0);
  options.features.max_range_m = 0.1;
  EXPECT_THROW(BuildSimulation(options), std::invalid_argument);
}

}  // namespace
}  // namespace vio::tools
