// Surfaces textured with the real V1_01 micro clip: texels are the image's
// pixels, rendered frames carry real structure and are deterministic per seed.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>

#include "test_data.h"
#include "vio/simulator/simulator.h"
#include "vio/simulator/texture.h"

namespace vio::tools {
namespace {

namespace fs = std::filesystem;

std::string ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(SimulatorTextureRealTest, TexelsAreTheCroppedImagesPixels) {
  const std::string micro = test::EurocSequence("V1_01_easy_micro");
  VIO_REQUIRE_DATA(micro);
  ImageTextureOptions options;
  options.dirs = micro;
  options.max_images_per_dir = 2;
  options.crop = 0.5;
  const ImageTextures textures = LoadImageTextures(options);
  ASSERT_EQ(textures.pyramids.size(), 2u);
  const cv::Mat& level0 = textures.pyramids[0][0];
  EXPECT_EQ(level0.cols, 376);
  EXPECT_EQ(level0.rows, 240);
  EXPECT_GE(textures.pyramids[0].size(), 4u);
  // The first image of the folder, its centre half.
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(micro + "/mav0/cam0/data")) files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  const cv::Mat image = cv::imread(files.front().string(), cv::IMREAD_GRAYSCALE);
  for (int y = 0; y < 240; y += 37) {
    for (int x = 0; x < 376; x += 41) {
      EXPECT_FLOAT_EQ(textures.Sample(0, x + 0.5f, y + 0.5f, 1.0f), image.at<std::uint8_t>(y + 120, x + 188));
    }
  }
  // Mirrored repeat (period 2 x 376): texel 1503 is texel 0.
  EXPECT_FLOAT_EQ(textures.Sample(0, 4 * 376 - 0.5f, 10.5f, 1.0f), level0.at<float>(10, 0));
  // A footprint of 4 texels reads the third level (two pyrDowns).
  EXPECT_FLOAT_EQ(textures.Sample(0, 4 * 10 + 2.0f, 4 * 7 + 2.0f, 4.0f), textures.pyramids[0][2].at<float>(7, 10));
}

TEST(SimulatorTextureRealTest, RenderedFramesHaveRealStructureAndDependOnTheSeedOnly) {
  const std::string micro = test::EurocSequence("V1_01_easy_micro");
  VIO_REQUIRE_DATA(micro);
  const std::string base = test::MakeTempDir("vio_texture_real");
  auto simulate = [&](const std::string& name, std::uint64_t seed) {
    SimulatorOptions options;
    options.output_dir = base + "/" + name;
    options.seed = seed;
    options.duration_s = 0.1;
    options.camera_output = SimCameraOutput::kImages;
    options.textures.dirs = micro;
    Simulate(options);
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(options.output_dir + "/mav0/cam0/data")) files.push_back(entry.path());
    std::sort(files.begin(), files.end());
    return files;
  };
  const std::vector<fs::path> a = simulate("a", 1), b = simulate("b", 1), c = simulate("c", 2);
  ASSERT_EQ(a.size(), 3u);
  ASSERT_EQ(b.size(), 3u);
  for (std::size_t i = 0; i < a.size(); ++i) EXPECT_EQ(ReadBytes(a[i]), ReadBytes(b[i])) << a[i];
  EXPECT_NE(ReadBytes(a[0]), ReadBytes(c[0]));
  const cv::Mat frame = cv::imread(a[0].string(), cv::IMREAD_GRAYSCALE);
  cv::Scalar mean, stddev;
  cv::meanStdDev(frame, mean, stddev);
  EXPECT_GT(stddev[0], 20.0);
  std::vector<cv::KeyPoint> corners;
  cv::FAST(frame, corners, 20, true);
  EXPECT_GT(corners.size(), 300u);
  fs::remove_all(base);
}

}  // namespace
}  // namespace vio::tools
