// ReadGreyImage gives cv::imread's grey pixels for every file, through its own
// decoding for 8-bit grey PNGs (stored or compressed), and nothing for a file
// that is damaged or no image.
#include <fstream>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "test_data.h"
#include "vio/dataset/image_file.h"

namespace vio::tools {
namespace {

cv::Mat Noise(int rows, int cols, int type, unsigned seed) {
  cv::Mat image(rows, cols, type);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0, 256);
  cv::GaussianBlur(image, image, cv::Size(3, 3), 0.7);  // smooth parts: every PNG filter gets used
  return image;
}

std::vector<char> Bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<char>(std::istreambuf_iterator<char>(in), {});
}

void Write(const std::string& path, const std::vector<char>& bytes) {
  std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

void ExpectSameAsImread(const std::string& path) {
  const cv::Mat expected = cv::imread(path, cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(expected.empty()) << path;
  const cv::Mat got = ReadGreyImage(path);
  ASSERT_EQ(got.type(), CV_8UC1) << path;
  ASSERT_EQ(got.size(), expected.size()) << path;
  EXPECT_EQ(cv::norm(got, expected, cv::NORM_INF), 0.0) << path;
}

TEST(ReadGreyImage, GivesImreadsPixelsForEveryKindOfFile) {
  const std::string dir = test::MakeTempDir("image_file");
  const cv::Mat grey = Noise(48, 75, CV_8UC1, 1);
  const cv::Mat odd = Noise(47, 1, CV_8UC1, 5);  // rows decoded in pairs: an odd count, one pixel per row
  for (int level : {0, 1, 9}) {  // 0: stored, as the EuRoC PNGs
    for (const cv::Mat& image : {grey, odd}) {
      const std::string path = dir + "/grey" + std::to_string(level) + "_" + std::to_string(image.rows) + ".png";
      ASSERT_TRUE(cv::imwrite(path, image, {cv::IMWRITE_PNG_COMPRESSION, level}));
      ExpectSameAsImread(path);
      EXPECT_EQ(cv::norm(ReadGreyImage(path), image, cv::NORM_INF), 0.0);
    }
  }
  cv::Mat deep;
  Noise(30, 41, CV_8UC1, 2).convertTo(deep, CV_16UC1, 257.0);
  const cv::Mat colour = Noise(30, 41, CV_8UC3, 3);
  ASSERT_TRUE(cv::imwrite(dir + "/deep.png", deep));
  ASSERT_TRUE(cv::imwrite(dir + "/colour.png", colour));
  ASSERT_TRUE(cv::imwrite(dir + "/grey.jpg", grey));
  ASSERT_TRUE(cv::imwrite(dir + "/colour.jpg", colour));
  for (const char* name : {"/deep.png", "/colour.png", "/grey.jpg", "/colour.jpg"}) ExpectSameAsImread(dir + name);
}

TEST(ReadGreyImage, GivesNothingForADamagedFileOrNoImage) {
  const std::string dir = test::MakeTempDir("image_file_bad");
  const std::string good = dir + "/good.png";
  ASSERT_TRUE(cv::imwrite(good, Noise(48, 75, CV_8UC1, 4), {cv::IMWRITE_PNG_COMPRESSION, 0}));
  const std::vector<char> bytes = Bytes(good);
  ASSERT_GT(bytes.size(), 3000u);
  // One pixel byte changed inside the (stored) image data: its chunk's CRC fails.
  std::vector<char> flipped = bytes;
  flipped[bytes.size() / 2] = static_cast<char>(flipped[bytes.size() / 2] ^ 0x10);
  Write(dir + "/flipped.png", flipped);
  EXPECT_TRUE(ReadGreyImage(dir + "/flipped.png").empty());
  Write(dir + "/truncated.png", std::vector<char>(bytes.begin(), bytes.begin() + bytes.size() / 2));
  EXPECT_TRUE(ReadGreyImage(dir + "/truncated.png").empty());
  Write(dir + "/header.png", std::vector<char>(bytes.begin(), bytes.begin() + 20));
  EXPECT_TRUE(ReadGreyImage(dir + "/header.png").empty());
  const std::string text = "no image here\n";
  Write(dir + "/text.png", std::vector<char>(text.begin(), text.end()));
  EXPECT_TRUE(ReadGreyImage(dir + "/text.png").empty());
  EXPECT_TRUE(ReadGreyImage(dir + "/missing.png").empty());
  EXPECT_TRUE(ReadGreyImage(dir).empty());
}

}  // namespace
}  // namespace vio::tools
