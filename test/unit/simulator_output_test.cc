// `Simulate` writes a complete, readable ASL folder, byte-identical for the
// same seed and different for another seed.
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>

#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/dataset/euroc_dataset.h"
#include "vio/simulator/simulator.h"

namespace vio::tools {
namespace {

namespace fs = std::filesystem;

// Relative path -> contents of every file under `root`.
std::map<std::string, std::string> ReadTree(const std::string& root) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    if (!entry.is_regular_file()) continue;
    std::ifstream in(entry.path(), std::ios::binary);
    files[fs::relative(entry.path(), root).string()] =
        std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  return files;
}

SimulatorOptions Options(const std::string& dir, std::uint64_t seed, SimCameraOutput output, double duration_s) {
  SimulatorOptions options;
  options.output_dir = dir;
  options.seed = seed;
  options.camera_output = output;
  options.duration_s = duration_s;
  return options;
}

void ExpectSameTrees(const std::map<std::string, std::string>& a, const std::map<std::string, std::string>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [path, contents] : a) {
    ASSERT_TRUE(b.count(path)) << path;
    EXPECT_TRUE(contents == b.at(path)) << path << " differs";
  }
}

TEST(SimulateOutputTest, FeaturesSameSeedIsByteIdenticalOtherSeedDiffers) {
  const std::string base = test::MakeTempDir("vio_sim_features");
  const SimulationSummary summary = Simulate(Options(base + "/a", 5, SimCameraOutput::kFeatures, 4.0));
  Simulate(Options(base + "/b", 5, SimCameraOutput::kFeatures, 4.0));
  Simulate(Options(base + "/c", 6, SimCameraOutput::kFeatures, 4.0));
  const auto a = ReadTree(base + "/a"), b = ReadTree(base + "/b"), c = ReadTree(base + "/c");
  for (const char* file : {"mav0/imu0/data.csv", "mav0/cam0/data.csv", "mav0/cam1/data.csv",
                           "mav0/state_groundtruth_estimate0/data.csv", "mav0/features0/data.csv",
                           "mav0/cam0/sensor.yaml", "mav0/imu0/sensor.yaml", "mav0/body.yaml"}) {
    EXPECT_TRUE(a.count(file)) << "missing " << file;
  }
  ExpectSameTrees(a, b);
  EXPECT_NE(a.at("mav0/features0/data.csv"), c.at("mav0/features0/data.csv"));
  EXPECT_NE(a.at("mav0/imu0/data.csv"), c.at("mav0/imu0/data.csv"));
  EXPECT_EQ(summary.frames, 81);
  fs::remove_all(base);
}

TEST(SimulateOutputTest, WrittenFolderReadsBackComplete) {
  const std::string dir = test::MakeTempDir("vio_sim_readback");
  const SimulatorOptions options = Options(dir, 3, SimCameraOutput::kFeatures, 4.0);
  const Simulation sim = BuildSimulation(options);
  WriteSimulation(sim, options);
  const EurocDataset read = ReadEuroc(dir);
  EXPECT_EQ(read.imu.size(), sim.dataset.imu.size());
  EXPECT_EQ(read.groundtruth.size(), sim.dataset.imu.size());  // 200 Hz with velocity and biases
  EXPECT_EQ(read.frames[0].size(), sim.frames.size());
  EXPECT_EQ(read.frames[1].size(), sim.frames.size());
  ASSERT_EQ(read.features.size(), sim.dataset.features.size());
  EXPECT_LT((read.features.back().uv_px - sim.dataset.features.back().uv_px).norm(), 1e-6);
  EXPECT_LT((read.groundtruth.back().accel_bias - sim.dataset.groundtruth.back().accel_bias).norm(), 1e-6);
  EXPECT_EQ(read.cameras[1].distortion_model, "radial-tangential");
  EXPECT_LT((read.cameras[1].T_b_c.matrix() - EurocStereoCalibration()[1].T_b_c.matrix()).norm(), 1e-9);
  fs::remove_all(dir);
}

TEST(SimulateOutputTest, ImagesSameSeedIsByteIdentical) {
  const std::string base = test::MakeTempDir("vio_sim_images");
  Simulate(Options(base + "/a", 5, SimCameraOutput::kImages, 0.2));
  Simulate(Options(base + "/b", 5, SimCameraOutput::kImages, 0.2));
  const auto a = ReadTree(base + "/a"), b = ReadTree(base + "/b");
  ExpectSameTrees(a, b);
  EXPECT_EQ(a.count("mav0/features0/data.csv"), 0u);
  int pngs = 0;
  for (const auto& [path, contents] : a) pngs += path.size() > 4 && path.substr(path.size() - 4) == ".png";
  EXPECT_EQ(pngs, 2 * 5);
  const EurocDataset read = ReadEuroc(base + "/a");  // checks every listed image exists
  EXPECT_TRUE(read.has_images);
  fs::remove_all(base);
}

// --noise_seed draws the images' sensor noise too: same trajectory and
// scene, other pixels; the same noise seed repeats them.
TEST(SimulateOutputTest, ImagesNoiseSeedChangesTheSensorNoiseOnly) {
  const std::string base = test::MakeTempDir("vio_sim_image_noise");
  SimulatorOptions options = Options(base + "/a", 5, SimCameraOutput::kImages, 0.2);
  options.noise_seed = 7;
  Simulate(options);
  options.output_dir = base + "/b";
  Simulate(options);
  options.output_dir = base + "/c";
  options.noise_seed = 8;
  Simulate(options);
  const auto a = ReadTree(base + "/a"), b = ReadTree(base + "/b"), c = ReadTree(base + "/c");
  ExpectSameTrees(a, b);
  EXPECT_EQ(a.at("mav0/scene.csv"), c.at("mav0/scene.csv"));
  EXPECT_EQ(a.at("mav0/cam0/data.csv"), c.at("mav0/cam0/data.csv"));
  int differing_pngs = 0;
  for (const auto& [path, contents] : a) {
    if (path.size() > 4 && path.substr(path.size() - 4) == ".png") differing_pngs += contents != c.at(path);
  }
  EXPECT_EQ(differing_pngs, 2 * 5);
  fs::remove_all(base);
}

// A hybrid sequence cut S s in (from_start_s) is the whole sequence's simulation
// with its start removed: from the cut on, the same features (tracks, pixel
// noise), IMU and ground truth; a cut run is then comparable with the span of a
// full run on the same measurements.
TEST(SimulateOutputTest, CutHybridSequenceIsTheWholeSequenceFromTheCutOn) {
  const std::string base = test::MakeTempDir("vio_sim_cut");
  Simulate(Options(base + "/source", 3, SimCameraOutput::kFeatures, 8.0));
  SimulatorOptions whole = Options(base + "/whole", 1, SimCameraOutput::kFeatures, 0.0);
  whole.from_euroc_dir = base + "/source";
  SimulatorOptions cut = whole;
  cut.output_dir = base + "/cut";
  cut.from_start_s = 5.0;
  const Simulation a = BuildSimulation(whole);
  const Simulation b = BuildSimulation(cut);
  ASSERT_FALSE(b.frames.empty());
  const Timestamp t0 = b.frames.front().t_ns;
  EXPECT_GE(t0, a.frames.front().t_ns + SecondsToNanos(5.0));
  std::vector<FeatureObservation> tail;
  for (const FeatureObservation& o : a.dataset.features) {
    if (o.t_ns >= t0) tail.push_back(o);
  }
  ASSERT_EQ(tail.size(), b.dataset.features.size());
  ASSERT_FALSE(tail.empty());
  for (std::size_t i = 0; i < tail.size(); ++i) {
    ASSERT_EQ(tail[i].t_ns, b.dataset.features[i].t_ns) << i;
    ASSERT_EQ(tail[i].feature_id, b.dataset.features[i].feature_id) << i;
    ASSERT_EQ(tail[i].camera, b.dataset.features[i].camera) << i;
    ASSERT_EQ(tail[i].uv_px, b.dataset.features[i].uv_px) << i;
  }
  ASSERT_EQ(b.features.cam0_count.size(), b.frames.size());
  EXPECT_EQ(b.features.cam0_count.back(), a.features.cam0_count.back());
  EXPECT_EQ(b.dataset.frames[0].front().t_ns, t0);
  ASSERT_FALSE(b.dataset.imu.empty());
  EXPECT_LE(b.dataset.imu.front().t_ns, t0);
  fs::remove_all(base);
}

TEST(SimulateOutputTest, RejectsBadOptions) {
  EXPECT_THROW(Simulate(Options("", 1, SimCameraOutput::kFeatures, 4.0)), std::invalid_argument);
  const std::string dir = test::MakeTempDir("vio_sim_bad");
  EXPECT_THROW(Simulate(Options(dir, 1, SimCameraOutput::kFeatures, -1.0)), std::invalid_argument);
  SimulatorOptions options = Options(dir, 1, SimCameraOutput::kImages, 1.0);
  options.png_compression = 12;
  EXPECT_THROW(Simulate(options), std::invalid_argument);
  options = Options(dir, 1, SimCameraOutput::kFeatures, 1.0);
  options.scene.room_size_m = Eigen::Vector3d(2.5, 8.0, 4.0);  // no room for the flight
  EXPECT_THROW(Simulate(options), std::invalid_argument);
  options = Options(dir, 1, SimCameraOutput::kFeatures, 1.0);
  options.from_euroc_dir = dir + "/does_not_exist";
  EXPECT_THROW(Simulate(options), DatasetError);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace vio::tools
