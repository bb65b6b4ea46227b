// Both image front ends end to end on a short synthetic sequence rendered
// into images (`vio simulate --camera=images`, made in the test's temp dir),
// then `vio run` with SWF(10): the run completes and the ATE stays small; the
// KLT run is the default one for a dataset with images and no features0; one
// and two pipeline threads give the same bytes.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "test_data.h"

namespace vio {
namespace {

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The number after the first `"key": ` following `after` in a JSON text.
double JsonNumber(const std::string& json, const std::string& after, const std::string& key) {
  const size_t start = json.find("\"" + after + "\"");
  const size_t at = json.find("\"" + key + "\": ", start == std::string::npos ? 0 : start);
  if (at == std::string::npos) ADD_FAILURE() << "no " << key << " in " << json;
  return at == std::string::npos ? -1.0 : std::strtod(json.c_str() + at + key.size() + 4, nullptr);
}

int RunVio(const std::string& arguments, const std::string& log) {
  const std::string command = std::string(VIO_BINARY) + " " + arguments + " > " + log + " 2>&1";
  return std::system(command.c_str());
}

class FrontendRendered : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = test::MakeTempDir("frontend_rendered");
    ASSERT_EQ(RunVio("simulate --camera=images --duration_s=8 --seed=3 --output_dir=" + dir_ + "/data",
                  dir_ + "/simulate.log"),
              0)
        << "see " << dir_ << "/simulate.log";
  }

  // `vio run` with `flags`; the front end that ran must be `frontend`.
  static void ExpectAteBelow(const std::string& frontend, const std::string& flags, double bound_m) {
    const std::string out = dir_ + "/" + frontend;
    ASSERT_EQ(RunVio("run --dataset=" + dir_ + "/data --output_dir=" + out + " " + flags +
                      " --policy=swf --window_size=10",
                  out + ".log"),
              0)
        << "see " << out << ".log";
    const std::string summary = ReadFile(out + "/summary.json");
    EXPECT_NE(summary.find("\"source\": \"" + frontend + "\""), std::string::npos) << summary;
    EXPECT_NE(ReadFile(out + "/config.yaml").find("frontend: \"" + frontend + "\""), std::string::npos);
    EXPECT_NE(summary.find("\"status\": \"ok\""), std::string::npos) << summary;
    const double ate = JsonNumber(summary, "ate", "rmse_m");
    EXPECT_GE(ate, 0.0);
    EXPECT_LE(ate, bound_m) << frontend;
    EXPECT_GE(JsonNumber(summary, "features_per_frame", "mean"), 50.0) << frontend;
    ::testing::Test::RecordProperty(frontend + "_ate_rmse_m", std::to_string(ate));
  }

  static std::string dir_;
};

std::string FrontendRendered::dir_;

// The rendered dataset has images and no features0: without a --frontend
// flag the run takes the KLT front end and says so.
TEST_F(FrontendRendered, KltByDefaultOnImagesOnly) {
  ExpectAteBelow("klt", "", 0.1);
  EXPECT_NE(ReadFile(dir_ + "/klt.log").find("running the klt front end on the images"), std::string::npos);
}

// The rendered folder as a ROS bag (`vio convert`) gives the KLT run the same
// trajectory (image runs agree to the last digits, not bit for bit).
TEST_F(FrontendRendered, BagGivesTheFolderTrajectory) {
  const std::string bag = dir_ + "/data.bag";
  ASSERT_EQ(RunVio("convert --input=" + dir_ + "/data --output=" + bag, dir_ + "/convert.log"), 0);
  ASSERT_EQ(RunVio("run --dataset=" + bag + " --calibration=" + dir_ + "/data --output_dir=" + dir_ +
                       "/bag_run --frontend=klt --policy=swf --window_size=10",
                   dir_ + "/bag_run.log"),
            0)
      << "see " << dir_ << "/bag_run.log";
  ASSERT_EQ(RunVio("run --dataset=" + dir_ + "/data --output_dir=" + dir_ +
                       "/folder_run --frontend=klt --policy=swf --window_size=10",
                   dir_ + "/folder_run.log"),
            0);
  std::istringstream a(ReadFile(dir_ + "/bag_run/trajectory.txt")), b(ReadFile(dir_ + "/folder_run/trajectory.txt"));
  std::string line_a, line_b;
  int rows = 0;
  while (std::getline(a, line_a) && std::getline(b, line_b)) {
    if (line_a.empty() || line_a[0] == '#') continue;
    std::istringstream ra(line_a), rb(line_b);
    double va = 0, vb = 0;
    for (int column = 0; column < 8 && (ra >> va) && (rb >> vb); ++column) EXPECT_NEAR(va, vb, 1e-6) << line_a;
    ++rows;
  }
  EXPECT_GT(rows, 100);
  EXPECT_FALSE(std::getline(b, line_b)) << "the folder run has more rows";
}

TEST_F(FrontendRendered, Brisk) { ExpectAteBelow("brisk", "--frontend=brisk", 0.1); }

// The pipeline's second thread (reading, decoding and the pyramids ahead of
// the tracking) changes nothing: trajectories and observations byte for byte
// equal to the one-thread run, for both image front ends.
TEST_F(FrontendRendered, PipelineThreadsGiveTheSameBytes) {
  for (const std::string frontend : {"klt", "brisk"}) {
    std::string files[2][2];
    for (int threads = 1; threads <= 2; ++threads) {
      const std::string out = dir_ + "/" + frontend + "_threads_" + std::to_string(threads);
      ASSERT_EQ(RunVio("run --dataset=" + dir_ + "/data --output_dir=" + out + " --frontend=" + frontend +
                           " --pipeline_threads=" + std::to_string(threads) +
                           " --policy=msckf --window_size=10 --output_observations",
                       out + ".log"),
                0)
          << "see " << out << ".log";
      files[threads - 1][0] = ReadFile(out + "/trajectory.txt");
      files[threads - 1][1] = ReadFile(out + "/observations.csv");
      EXPECT_NE(ReadFile(out + "/summary.json").find("\"pipeline_threads\": " + std::to_string(threads)),
                std::string::npos);
    }
    EXPECT_GT(files[0][0].size(), 10000u) << frontend;
    EXPECT_GT(files[0][1].size(), 100000u) << frontend;
    EXPECT_TRUE(files[0][0] == files[1][0]) << frontend << ": trajectories differ";
    EXPECT_TRUE(files[0][1] == files[1][1]) << frontend << ": observations differ";
  }
}

// An image that cannot be decoded mid-run stops the run with status failed,
// naming the file, whichever thread decoded it; what was estimated before is
// kept, the same for one and two pipeline threads. (The dataset links to the
// rendered files; one image is replaced by a few bytes of text.)
TEST_F(FrontendRendered, AnUnreadableImageStopsTheRunAlikeForOneAndTwoThreads) {
  namespace fs = std::filesystem;
  const fs::path from = fs::path(dir_) / "data", to = fs::path(dir_) / "broken";
  fs::remove_all(to);
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(from)) {
    const fs::path target = to / fs::relative(entry.path(), from);
    if (entry.is_directory()) {
      fs::create_directories(target);
    } else {
      fs::create_symlink(entry.path(), target);
    }
  }
  std::ifstream frames(from / "mav0/cam1/data.csv");
  std::string line;
  for (int row = 0; row <= 60 && std::getline(frames, line);) row += !line.empty() && line[0] != '#';
  const std::string name = line.substr(line.find(',') + 1, line.find_first_of("\r\n", line.find(',')) - line.find(',') - 1);
  const fs::path broken = to / "mav0/cam1/data" / name;
  ASSERT_TRUE(fs::is_symlink(broken)) << broken;
  fs::remove(broken);
  std::ofstream(broken) << "not an image";
  std::string trajectories[2];
  for (int threads = 1; threads <= 2; ++threads) {
    const std::string out = dir_ + "/broken_threads_" + std::to_string(threads);
    EXPECT_NE(RunVio("run --dataset=" + to.string() + " --output_dir=" + out + " --frontend=klt --pipeline_threads=" +
                         std::to_string(threads) + " --policy=msckf --window_size=10",
                     out + ".log"),
              0);
    const std::string summary = ReadFile(out + "/summary.json");
    EXPECT_NE(summary.find("\"status\": \"failed\""), std::string::npos) << summary;
    EXPECT_NE(summary.find(name + ": cannot read the image"), std::string::npos) << summary;
    trajectories[threads - 1] = ReadFile(out + "/trajectory.txt");
  }
  EXPECT_GT(trajectories[0].size(), 1000u);
  EXPECT_TRUE(trajectories[0] == trajectories[1]);
}

}  // namespace
}  // namespace vio
