#include "vio/dataset/scene_csv.h"

#include "csv_reader.h"
#include "text_writer.h"

namespace vio::tools {
namespace {

const std::vector<std::string> kSceneCsvColumns = {"kind",      "min_x [m]", "min_y [m]", "min_z [m]",
                                           "max_x [m]", "max_y [m]", "max_z [m]"};

void AddRow(const char* kind, const Eigen::AlignedBox3d& box, TextWriter* out) {
  out->Text(kind);
  for (const Eigen::Vector3d& corner : {box.min(), box.max()}) {
    for (int k = 0; k < 3; ++k) out->Text(",").Double(corner[k]);
  }
  out->Text("\n");
}

}  // namespace

void WriteSceneCsv(const SceneBoxes& scene, const std::string& path) {
  TextWriter out(path);
  out.Header(kSceneCsvColumns);
  AddRow("room", scene.room, &out);
  for (const Eigen::AlignedBox3d& box : scene.boxes) AddRow("box", box, &out);
  out.Save();
}

SceneBoxes ReadSceneCsv(const std::string& path) {
  CsvReader reader(path, kSceneCsvColumns);
  SceneBoxes scene;
  bool has_room = false;
  while (reader.NextRow()) {
    const Eigen::Vector3d min(reader.Double(1), reader.Double(2), reader.Double(3));
    const Eigen::Vector3d max(reader.Double(4), reader.Double(5), reader.Double(6));
    if (!(min.array() < max.array()).all()) reader.Fail("a box's minimum must be below its maximum on every axis");
    const std::string_view kind = reader.Field(0);
    if (kind == "room") {
      if (has_room) reader.Fail("a second room");
      scene.room = Eigen::AlignedBox3d(min, max);
      has_room = true;
    } else if (kind == "box") {
      scene.boxes.emplace_back(min, max);
    } else {
      reader.Fail("kind must be room or box, got '" + std::string(kind) + "'");
    }
  }
  if (!has_room) throw DatasetError(path + ": no room row");
  return scene;
}

}  // namespace vio::tools
