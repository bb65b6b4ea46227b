// mav0/scene.csv and a run's observations.csv: exact round trips, and every
// malformed row reported with its file and line.
#include <cmath>
#include <fstream>
#include <functional>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_data.h"
#include "vio/dataset/euroc_dataset.h"
#include "vio/dataset/observations_csv.h"
#include "vio/dataset/scene_csv.h"

namespace vio::tools {
namespace {

using ::testing::HasSubstr;
using test::MakeTempDir;

std::string WriteText(const std::string& dir, const std::string& name, const std::string& text) {
  const std::string path = dir + "/" + name;
  std::ofstream(path) << text;
  return path;
}

std::string ErrorOf(const std::function<void()>& read) {
  try {
    read();
  } catch (const DatasetError& e) {
    return e.what();
  }
  return "no error";
}

TEST(SceneCsv, RoundTripsExactly) {
  const std::string dir = MakeTempDir("scene_csv");
  SceneBoxes scene;
  scene.room = Eigen::AlignedBox3d(Eigen::Vector3d(-4.75, -3.3, 0.0), Eigen::Vector3d(3.25, 4.7, 4.0));
  scene.boxes.emplace_back(Eigen::Vector3d(0.1 / 3, 1.0, 0.0), Eigen::Vector3d(0.5, 1.7, 1.4024938527022948));
  WriteSceneCsv(scene, dir + "/mav0/scene.csv");
  const SceneBoxes back = ReadSceneCsv(dir + "/mav0/scene.csv");
  EXPECT_EQ(back.room.min(), scene.room.min());
  EXPECT_EQ(back.room.max(), scene.room.max());
  ASSERT_EQ(back.boxes.size(), 1u);
  EXPECT_EQ(back.boxes[0].min(), scene.boxes[0].min());
  EXPECT_EQ(back.boxes[0].max(), scene.boxes[0].max());
}

TEST(SceneCsv, MalformedRowsNameTheirLine) {
  const std::string dir = MakeTempDir("scene_csv_bad");
  const std::string header = "#kind,min_x,min_y,min_z,max_x,max_y,max_z\n";
  const std::string room = "room,-1,-1,0,1,1,3\n";
  EXPECT_THAT(ErrorOf([&] { ReadSceneCsv(WriteText(dir, "a.csv", header + room + "shelf,0,0,0,1,1,1\n")); }),
              HasSubstr("a.csv:3: kind must be room or box, got 'shelf'"));
  EXPECT_THAT(ErrorOf([&] { ReadSceneCsv(WriteText(dir, "b.csv", header + room + "box,0,0,1,1,1,1\n")); }),
              HasSubstr("b.csv:3: a box's minimum must be below its maximum"));
  EXPECT_THAT(ErrorOf([&] { ReadSceneCsv(WriteText(dir, "c.csv", header + room + room)); }),
              HasSubstr("c.csv:3: a second room"));
  EXPECT_THAT(ErrorOf([&] { ReadSceneCsv(WriteText(dir, "d.csv", header + "box,0,0,0,1,1,1\n")); }),
              HasSubstr("d.csv: no room row"));
  EXPECT_THAT(ErrorOf([&] { ReadSceneCsv(WriteText(dir, "e.csv", header + "room,-1,-1,0,1,1\n")); }),
              HasSubstr("e.csv:2:"));
  EXPECT_THAT(ErrorOf([&] { ReadSceneCsv(dir + "/missing.csv"); }), HasSubstr("missing.csv"));
}

TEST(ObservationsCsv, RoundTripsFramesExactly) {
  const std::string dir = MakeTempDir("observations_csv");
  const std::vector<StereoFrame> frames = {
      {100, {{LandmarkId{3}, Eigen::Vector3d(630.9666638158989, 617.0496689243708, 125.18148703953813)},
             {LandmarkId{7}, Eigen::Vector3d(0.1, -0.2, 1.0 / 3)}}},
      {150, {}},  // no observations: no rows, so not read back
      {200, {{LandmarkId{3}, Eigen::Vector3d(600.5, 590.25, 126.0)}}}};
  {
    ObservationsCsvWriter writer(dir + "/observations.csv");
    for (const StereoFrame& frame : frames) writer.Add(frame);
    writer.Close();
  }
  const std::vector<StereoFrame> back = ReadObservationsCsv(dir + "/observations.csv");
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[0].t_ns, 100);
  EXPECT_EQ(back[1].t_ns, 200);
  ASSERT_EQ(back[0].observations.size(), 2u);
  EXPECT_EQ(back[0].observations[1].landmark, LandmarkId{7});
  EXPECT_EQ(back[0].observations[0].z_px, frames[0].observations[0].z_px);
  EXPECT_EQ(back[0].observations[1].z_px, frames[0].observations[1].z_px);
  EXPECT_EQ(back[1].observations[0].z_px, frames[2].observations[0].z_px);
}

TEST(ObservationsCsv, MalformedRowsNameTheirLine) {
  const std::string dir = MakeTempDir("observations_csv_bad");
  const std::string header = "#timestamp [ns],landmark_id,u_L [px],u_R [px],v [px]\n";
  EXPECT_THAT(ErrorOf([&] { ReadObservationsCsv(WriteText(dir, "a.csv", header + "10,1,1,1,1\n10,1,2,2,2\n")); }),
              HasSubstr("a.csv:3: landmark 1 twice in one frame"));
  EXPECT_THAT(ErrorOf([&] { ReadObservationsCsv(WriteText(dir, "b.csv", header + "10,1,1,1,1\n9,2,2,2,2\n")); }),
              HasSubstr("b.csv:3:"));
  EXPECT_THAT(ErrorOf([&] { ReadObservationsCsv(WriteText(dir, "c.csv", header + "10,1,1,x,1\n")); }),
              HasSubstr("c.csv:2:"));
  StereoFrame bad{10, {{LandmarkId{1}, Eigen::Vector3d(1.0, std::nan(""), 2.0)}}};
  ObservationsCsvWriter writer(dir + "/d.csv");
  EXPECT_THROW(writer.Add(bad), DatasetError);
}

}  // namespace
}  // namespace vio::tools
