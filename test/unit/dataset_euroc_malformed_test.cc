// Table of malformed EuRoC inputs: each row is a small file written to a
// fresh temp folder, the reader to call, and the error it must raise (a
// DatasetError whose message names the file and the 1-based line).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cctype>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "test_data.h"
#include "vio/dataset/euroc_dataset.h"

namespace vio::tools {
namespace {

using ::testing::HasSubstr;

/// Reads something under `dir`; `file` is the full path of the case's file.
using Reader = std::function<void(const std::string& dir, const std::string& file)>;

struct MalformedInput {
  std::string name;
  std::string file;                    ///< relative to the temp folder
  std::optional<std::string> content;  ///< not written when absent
  Reader reader;
  std::string expected;  ///< substring of the error message
};

struct MalformedCase {
  MalformedInput input;
  bool seed_dataset = false;        ///< write a valid sequence first, then `file` over it
  std::vector<std::string> images;  ///< image files created (relative) before reading
};

MalformedCase Case(MalformedInput input, bool seed_dataset = false,
                   std::vector<std::string> images = {}) {
  return {std::move(input), seed_dataset, std::move(images)};
}

const Reader kImu = [](const std::string&, const std::string& f) { ReadImuCsv(f); };
const Reader kGroundTruth = [](const std::string&, const std::string& f) { ReadGroundTruthCsv(f); };
const Reader kTum = [](const std::string&, const std::string& f) { ReadTumTrajectory(f); };
const Reader kCameraCsv = [](const std::string&, const std::string& f) { ReadCameraCsv(f); };
const Reader kFeatures = [](const std::string&, const std::string& f) { ReadFeaturesCsv(f); };
const Reader kCameraYaml = [](const std::string&, const std::string& f) { ReadCameraYaml(f); };
const Reader kImuYaml = [](const std::string&, const std::string& f) { ReadImuYaml(f); };
const Reader kDataset = [](const std::string& dir, const std::string&) { ReadEuroc(dir); };

const std::string kImuHeader =
    "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
    "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";
const std::string kImuRow1 = "1000,0.1,0.2,0.3,9.8,0.1,0.2\n";
const std::string kImuRow2 = "2000,0.1,0.2,0.3,9.8,0.1,0.2\n";
const std::string kFeaturesHeader = "#timestamp [ns],camera,feature_id,u [px],v [px]\n";
const std::string kTumHeader = "# timestamp(s) tx ty tz qx qy qz qw\n";

// A valid camera sensor.yaml with `line` (1-based, "" to drop it) replaced.
std::string CameraYamlWith(int line, const std::string& replacement) {
  const std::vector<std::string> lines = {
      "%YAML:1.0",                                              // 1
      "# General sensor definitions.",                          // 2
      "sensor_type: camera",                                    // 3
      "T_BS:",                                                  // 4
      "  cols: 4",                                              // 5
      "  rows: 4",                                              // 6
      "  data: [1.0, 0.0, 0.0, 0.1, 0.0, 1.0, 0.0, 0.2,",       // 7
      "         0.0, 0.0, 1.0, 0.3, 0.0, 0.0, 0.0, 1.0]",       // 8
      "rate_hz: 20",                                            // 9
      "resolution: [752, 480]",                                 // 10
      "camera_model: pinhole",                                  // 11
      "intrinsics: [458.654, 457.296, 367.215, 248.375]",       // 12
      "distortion_model: radial-tangential",                    // 13
      "distortion_coefficients: [-0.28, 0.07, 0.0002, 1e-05]",  // 14
  };
  std::string text;
  for (int i = 1; i <= static_cast<int>(lines.size()); ++i) {
    const std::string& l = i == line ? replacement : lines[i - 1];
    if (!l.empty()) text += l + "\n";
  }
  return text;
}

std::string ImuYamlWith(const std::string& gyro_noise_line) {
  return "%YAML:1.0\nsensor_type: imu\nT_BS:\n  cols: 4\n  rows: 4\n"
         "  data: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, "
         "1.0]\n"
         "rate_hz: 200\n" +
         gyro_noise_line +
         "\ngyroscope_random_walk: 1.9393e-05\naccelerometer_noise_density: 2.0e-3\n"
         "accelerometer_random_walk: 3.0e-3\n";
}

std::string GroundTruthRow(const std::string& t, const std::string& qw) {
  return t + ",1,2,3," + qw + ",0,0,0,0.1,0.2,0.3,0.01,0.02,0.03,0.1,0.2,0.3\n";
}

std::vector<MalformedCase> Cases() {
  return {
      Case({"imu missing file", "imu0/data.csv", std::nullopt, kImu, "imu0/data.csv: cannot open"}),
      Case({"imu empty file", "imu0/data.csv", "", kImu, "imu0/data.csv:1: empty: no data rows"}),
      Case({"imu header only", "imu0/data.csv", kImuHeader + "\n", kImu,
            "imu0/data.csv:2: empty: no data rows"}),
      Case({"imu too few columns", "imu0/data.csv",
            kImuHeader + kImuRow1 + "2000,0.1,0.2,0.3,9.8,0.1\n", kImu,
            "imu0/data.csv:3: wrong column count: expected 7, got 6"}),
      Case({"imu too many columns", "imu0/data.csv", kImuHeader + "1000,0.1,0.2,0.3,9.8,0.1,0.2,\n",
            kImu, "imu0/data.csv:2: wrong column count: expected 7, got 8"}),
      Case({"imu non-numeric field", "imu0/data.csv",
            kImuHeader + kImuRow1 + "2000,0.1,abc,0.3,9.8,0.1,0.2\n", kImu,
            "imu0/data.csv:3: column 3 (w_RS_S_y [rad s^-1]): non-numeric field \"abc\""}),
      Case({"imu trailing garbage", "imu0/data.csv", kImuHeader + "1000,0.1,0.2,0.3,9.8x,0.1,0.2\n",
            kImu, "imu0/data.csv:2: column 5 (a_RS_S_x [m s^-2]): non-numeric field \"9.8x\""}),
      Case({"imu empty field", "imu0/data.csv", kImuHeader + "1000,0.1,,0.3,9.8,0.1,0.2\n", kImu,
            "imu0/data.csv:2: column 3 (w_RS_S_y [rad s^-1]): non-numeric field \"\""}),
      Case(
          {"imu NaN", "imu0/data.csv", kImuHeader + "1000,0.1,0.2,0.3,nan,0.1,0.2\n", kImu,
           "imu0/data.csv:2: column 5 (a_RS_S_x [m s^-2]): non-finite value (NaN or inf) \"nan\""}),
      Case({"imu inf", "imu0/data.csv", kImuHeader + kImuRow1 + "2000,0.1,0.2,-inf,9.8,0.1,0.2\n",
            kImu,
            "imu0/data.csv:3: column 4 (w_RS_S_z [rad s^-1]): non-finite value (NaN or inf) "
            "\"-inf\""}),
      Case({"imu timestamp not an integer", "imu0/data.csv",
            kImuHeader + "1.5e3,0.1,0.2,0.3,9.8,0.1,0.2\n", kImu,
            "imu0/data.csv:2: column 1 (timestamp [ns]): not an integer: \"1.5e3\""}),
      Case({"imu timestamp overflow", "imu0/data.csv",
            kImuHeader + "99999999999999999999,0.1,0.2,0.3,9.8,0.1,0.2\n", kImu,
            "imu0/data.csv:2: column 1 (timestamp [ns]): not an integer"}),
      Case({"imu timestamp one past int64", "imu0/data.csv",
            kImuHeader + "9223372036854775808,0.1,0.2,0.3,9.8,0.1,0.2\n", kImu,
            "imu0/data.csv:2: column 1 (timestamp [ns]): not an integer"}),
      Case({"imu non-increasing timestamp", "imu0/data.csv",
            kImuHeader + kImuRow1 + kImuRow2 + "1500,0.1,0.2,0.3,9.8,0.1,0.2\n", kImu,
            "imu0/data.csv:4: non-increasing timestamp 1500 (after 2000 on line 3)"}),
      Case({"imu duplicated timestamp", "imu0/data.csv", kImuHeader + kImuRow1 + "# c\n" + kImuRow1,
            kImu, "imu0/data.csv:4: duplicated timestamp 1000 (same as 1000 on line 2)"}),
      Case({"imu CRLF error line", "imu0/data.csv",
            "#h\r\n1000,1,2,3,4,5,6\r\n\r\n2000,1,2,3,4,5\r\n", kImu,
            "imu0/data.csv:4: wrong column count: expected 7, got 6"}),
      Case({"ground truth 16 columns", "gt/data.csv",
            "#timestamp, p_RS_R_x [m]\n1000,1,2,3,1,0,0,0,0.1,0.2,0.3,0.01,0.02,0.03,0.1,0.2\n",
            kGroundTruth, "gt/data.csv:2: wrong column count: expected 17, got 16"}),
      Case({"ground truth quaternion not unit", "gt/data.csv",
            GroundTruthRow("1000", "1") + GroundTruthRow("2000", "0.5"), kGroundTruth,
            "gt/data.csv:2: quaternion norm 0.5"}),
      Case({"ground truth duplicated timestamp", "gt/data.csv",
            GroundTruthRow("1000", "1") + GroundTruthRow("1000", "1"), kGroundTruth,
            "gt/data.csv:2: duplicated timestamp 1000"}),
      Case({"ground truth missing", "gt/data.csv", std::nullopt, kGroundTruth,
            "gt/data.csv: cannot open"}),
      Case({"tum bad timestamp", "gt/groundtruth_tum.txt", kTumHeader + "12:30 0 0 0 0 0 0 1\n",
            kTum,
            "gt/groundtruth_tum.txt:2: column 1 (timestamp [s]): not decimal seconds: \"12:30\""}),
      Case({"tum non-increasing", "gt/groundtruth_tum.txt",
            kTumHeader + "2.5 0 0 0 0 0 0 1\n2.25 0 0 0 0 0 0 1\n", kTum,
            "gt/groundtruth_tum.txt:3: non-increasing timestamp 2250000000"}),
      Case({"tum wrong columns", "gt/groundtruth_tum.txt", kTumHeader + "2.5 0 0 0 0 0 1\n", kTum,
            "gt/groundtruth_tum.txt:2: wrong column count: expected 8, got 7"}),
      Case({"tum empty", "gt/groundtruth_tum.txt", kTumHeader, kTum,
            "gt/groundtruth_tum.txt:1: empty"}),
      Case({"camera csv empty filename", "cam0/data.csv",
            "#timestamp [ns],filename\n1000,a.png\n2000,\n", kCameraCsv,
            "cam0/data.csv:3: column 2 (filename): empty file name"}),
      Case({"camera csv duplicated timestamp", "cam0/data.csv",
            "#timestamp [ns],filename\n1000,a.png\n1000,b.png\n", kCameraCsv,
            "cam0/data.csv:3: duplicated timestamp 1000"}),
      Case({"listed image missing", "mav0/cam0/data.csv",
            "#timestamp [ns],filename\n1000,a.png\n2000,b.png\n3000,c.png\n", kDataset,
            "mav0/cam0/data.csv:3: listed image missing: "},
           /*seed_dataset=*/true, {"mav0/cam0/data/a.png"}),
      Case({"no mav0 folder", "x.txt", "", kDataset, ": missing mav0/"}),
      Case({"features bad camera index", "features0/data.csv",
            kFeaturesHeader + "1000,0,1,1,2\n1000,2,1,1,2\n", kFeatures,
            "features0/data.csv:3: camera index 2 is not 0 or 1"}),
      Case({"features negative id", "features0/data.csv", kFeaturesHeader + "1000,1,-4,1,2\n",
            kFeatures, "features0/data.csv:2: negative feature_id -4"}),
      Case({"features duplicated observation", "features0/data.csv",
            kFeaturesHeader + "1000,0,7,1,2\n1000,1,7,1,2\n1000,0,7,3,4\n", kFeatures,
            "features0/data.csv:4: duplicated observation (t, camera, feature_id) = (1000, 0, 7) "
            "(also on line 2)"}),
      Case({"features decreasing timestamp", "features0/data.csv",
            kFeaturesHeader + "2000,0,7,1,2\n1000,0,7,1,2\n", kFeatures,
            "features0/data.csv:3: non-increasing timestamp 1000"}),
      Case({"features inf pixel", "features0/data.csv", kFeaturesHeader + "2000,0,7,inf,2\n",
            kFeatures, "features0/data.csv:2: column 4 (u [px]): non-finite value"}),
      Case({"camera yaml missing file", "cam0/sensor.yaml", std::nullopt, kCameraYaml,
            "cam0/sensor.yaml: cannot open"}),
      Case({"camera yaml missing key", "cam0/sensor.yaml", CameraYamlWith(12, ""), kCameraYaml,
            "cam0/sensor.yaml:3: missing key 'intrinsics'"}),
      Case({"camera yaml T_BS 3 rows", "cam0/sensor.yaml", CameraYamlWith(6, "  rows: 3"),
            kCameraYaml,
            "cam0/sensor.yaml:5: T_BS must be 4x4 with 16 values, got rows 3, cols 4, 16 values"}),
      Case({"camera yaml T_BS 12 values", "cam0/sensor.yaml",
            CameraYamlWith(8, "         0.0, 0.0, 1.0, 0.3]"), kCameraYaml,
            "cam0/sensor.yaml:5: T_BS must be 4x4 with 16 values, got rows 4, cols 4, 12 values"}),
      Case({"camera yaml T_BS not a rotation", "cam0/sensor.yaml",
            CameraYamlWith(8, "         0.0, 0.0, 2.0, 0.3, 0.0, 0.0, 0.0, 1.0]"), kCameraYaml,
            "cam0/sensor.yaml:5: T_BS rotation is not orthonormal"}),
      Case({"camera yaml unknown distortion", "cam0/sensor.yaml",
            CameraYamlWith(13, "distortion_model: fisheye"), kCameraYaml,
            "cam0/sensor.yaml:13: unknown distortion_model 'fisheye'"}),
      Case({"camera yaml unknown camera model", "cam0/sensor.yaml",
            CameraYamlWith(11, "camera_model: omni"), kCameraYaml,
            "cam0/sensor.yaml:11: unknown camera_model 'omni'"}),
      Case({"camera yaml 3 intrinsics", "cam0/sensor.yaml",
            CameraYamlWith(12, "intrinsics: [458.6, 457.2, 367.2]"), kCameraYaml,
            "cam0/sensor.yaml:12: 'intrinsics' must be a list of 4 numbers, got 3 values"}),
      Case({"camera yaml zero width", "cam0/sensor.yaml",
            CameraYamlWith(10, "resolution: [0, 480]"), kCameraYaml,
            "cam0/sensor.yaml:10: 'resolution' must be positive"}),
      Case({"camera yaml negative focal length", "cam0/sensor.yaml",
            CameraYamlWith(12, "intrinsics: [-458.6, 457.2, 367.2, 248.3]"), kCameraYaml,
            "cam0/sensor.yaml:12: 'intrinsics' focal lengths fu, fv must be positive"}),
      Case({"camera yaml non-numeric rate", "cam0/sensor.yaml", CameraYamlWith(9, "rate_hz: fast"),
            kCameraYaml, "cam0/sensor.yaml:9: 'rate_hz' is not a number: \"fast\""}),
      Case({"camera yaml NaN intrinsic", "cam0/sensor.yaml",
            CameraYamlWith(12, "intrinsics: [458.6, .nan, 367, 248]"), kCameraYaml,
            "cam0/sensor.yaml:12: 'intrinsics[1]' is not"}),
      Case({"camera yaml syntax error", "cam0/sensor.yaml",
            CameraYamlWith(10, "resolution: [752, 480"), kCameraYaml,
            "cam0/sensor.yaml:11: YAML error"}),
      Case({"imu yaml negative noise", "imu0/sensor.yaml",
            ImuYamlWith("gyroscope_noise_density: -1.6968e-04"), kImuYaml,
            "imu0/sensor.yaml:8: 'gyroscope_noise_density' must be positive: \"-1.6968e-04\""}),
      Case({"imu yaml missing key", "imu0/sensor.yaml", ImuYamlWith(""), kImuYaml,
            "imu0/sensor.yaml:2: missing key 'gyroscope_noise_density'"}),
  };
}

void WriteFile(const std::string& path, const std::string& content) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream(path, std::ios::binary) << content;
}

void SeedValidSequence(const std::string& dir) {
  EurocDataset dataset;
  dataset.imu.resize(3);
  for (int i = 0; i < 3; ++i) dataset.imu[i].t_ns = 1000 * (i + 1);
  dataset.frames[0] = {{1000, "a.png"}};
  dataset.frames[1] = {{1000, "a.png"}};
  WriteEuroc(dataset, dir);
}

class EurocMalformed : public ::testing::TestWithParam<MalformedCase> {};

TEST_P(EurocMalformed, ThrowsNamingFileAndLine) {
  const MalformedCase& param = GetParam();
  const MalformedInput& c = param.input;
  const std::string dir = test::MakeTempDir("euroc_malformed");
  if (param.seed_dataset) SeedValidSequence(dir);
  const std::string file = dir + "/" + c.file;
  if (c.content.has_value()) WriteFile(file, *c.content);
  for (const std::string& image : param.images) WriteFile(dir + "/" + image, "img");
  try {
    c.reader(dir, file);
    ADD_FAILURE() << "no error for: " << c.name;
  } catch (const DatasetError& e) {
    EXPECT_THAT(e.what(), HasSubstr(c.expected));
    EXPECT_THAT(e.what(), HasSubstr(dir)) << "the message must name the file by its path";
  }
}

TEST(EurocMalformedTable, CoversEnoughCases) { EXPECT_GE(Cases().size(), 12u); }

TEST(EurocMalformedTable, MissingImageErrorNamesTheFirstMissingFile) {
  const std::string dir = test::MakeTempDir("euroc_first_missing");
  SeedValidSequence(dir);
  WriteFile(dir + "/mav0/cam0/data.csv",
            "#timestamp [ns],filename\n1000,a.png\n2000,b.png\n3000,c.png\n");
  WriteFile(dir + "/mav0/cam0/data/a.png", "img");
  try {
    ReadEuroc(dir);
    ADD_FAILURE() << "missing images not reported";
  } catch (const DatasetError& e) {
    EXPECT_THAT(e.what(), HasSubstr("listed image missing: " + dir + "/mav0/cam0/data/b.png"));
    EXPECT_THAT(e.what(), ::testing::Not(HasSubstr("c.png")));
  }
}

std::string CaseName(const ::testing::TestParamInfo<MalformedCase>& info) {
  std::string name;
  for (const char ch : info.param.input.name)
    name += std::isalnum(static_cast<unsigned char>(ch)) ? ch : '_';
  return name;
}

INSTANTIATE_TEST_SUITE_P(Table, EurocMalformed, ::testing::ValuesIn(Cases()), CaseName);

}  // namespace
}  // namespace vio::tools
