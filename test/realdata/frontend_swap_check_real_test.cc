// The stereo swap check (stereo_swap_check.h) on real EuRoC images (skipped when the data is absent):
// the V1_01_easy_micro and flight10 pairs as recorded are not exchanged; given the other way round
// (cam1's image as cam0's) they are, with a problem that names the fix.
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "euroc_calibration.h"
#include "test_data.h"
#include "vio/frontend/stereo_swap_check.h"

namespace vio::frontend {
namespace {

// The images of camN/data.csv, in order, read grey.
std::vector<cv::Mat> Images(const std::string& sequence, int camera) {
  const std::string folder = sequence + "/mav0/cam" + std::to_string(camera);
  std::ifstream in(folder + "/data.csv");
  std::vector<cv::Mat> images;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    if (line.back() == '\r') line.pop_back();
    images.push_back(cv::imread(folder + "/data/" + line.substr(line.find(',') + 1), cv::IMREAD_GRAYSCALE));
  }
  return images;
}

void Check(const std::string& sequence) {
  const StereoRectifier rectifier(test::EurocCamera(0), test::EurocCamera(1));
  const std::vector<cv::Mat> left = Images(sequence, 0), right = Images(sequence, 1);
  ASSERT_EQ(left.size(), right.size());
  StereoSwapCheck as_given(rectifier), exchanged(rectifier);
  for (std::size_t k = 0; k < left.size(); ++k) {
    as_given.Add(left[k], right[k]);
    exchanged.Add(right[k], left[k]);
  }
  ASSERT_TRUE(as_given.decided());
  ASSERT_TRUE(exchanged.decided());
  EXPECT_EQ(as_given.problem(), "");
  EXPECT_GE(as_given.matches_as_given(), StereoSwapCheck::kMinExchangedMatches);
  EXPECT_NE(exchanged.problem().find("are the cameras swapped?"), std::string::npos) << exchanged.problem();
  EXPECT_EQ(exchanged.matches_exchanged(), as_given.matches_as_given());
}

TEST(StereoSwapCheckReal, TheStaticClip) {
  const std::string micro = test::EurocSequence("V1_01_easy_micro");
  VIO_REQUIRE_DATA(micro);
  Check(micro);
}

TEST(StereoSwapCheckReal, TheFlight) {
  const std::string flight = test::EurocSequence("V1_01_easy_flight10");
  VIO_REQUIRE_DATA(flight);
  Check(flight);
}

}  // namespace
}  // namespace vio::frontend
