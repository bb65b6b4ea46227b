// Per-frame tables:
//  * camN/data.csv: "#timestamp [ns],filename", timestamps strictly increasing,
//    file names relative to camN/data/.
//  * features0/data.csv (this project's extension):
//    "#timestamp [ns],camera,feature_id,u [px],v [px]", timestamps
//    non-decreasing, camera 0 or 1, feature_id >= 0, each (t, camera, id) once.
#include <glog/logging.h>

#include <algorithm>
#include <filesystem>
#include <optional>
#include <utility>
#include <tuple>

#include "csv_reader.h"
#include "euroc_internal.h"
#include "text_writer.h"
#include "vio/dataset/euroc_dataset.h"

namespace vio::tools {
namespace {

const std::vector<std::string>& CameraColumns() {
  static const std::vector<std::string> kColumns = {"timestamp [ns]", "filename"};
  return kColumns;
}

const std::vector<std::string>& FeatureColumns() {
  static const std::vector<std::string> kColumns = {"timestamp [ns]", "camera", "feature_id",
                                                    "u [px]", "v [px]"};
  return kColumns;
}

auto SortKey(const FeatureObservation& f) {
  return std::make_tuple(f.t_ns, f.camera, f.feature_id);
}

std::string KeyText(const FeatureObservation& f) {
  return "(t, camera, feature_id) = (" + std::to_string(f.t_ns) + ", " + std::to_string(f.camera) +
         ", " + std::to_string(f.feature_id) + ")";
}

FeatureObservation ReadFeatureRow(const CsvReader& reader) {
  FeatureObservation f;
  f.t_ns = reader.Int64(0);
  const std::int64_t camera = reader.Int64(1);
  if (camera != 0 && camera != 1) {
    reader.Fail("camera index " + std::to_string(camera) + " is not 0 or 1");
  }
  f.camera = static_cast<int>(camera);
  f.feature_id = reader.Int64(2);
  if (f.feature_id < 0) reader.Fail("negative feature_id " + std::to_string(f.feature_id));
  f.uv_px = {reader.Double(3), reader.Double(4)};
  return f;
}

void CheckWritableFilename(const std::string& filename, const std::string& path) {
  const bool bad = filename.empty() || filename.front() == '#' ||
                   filename.find_first_of(",\r\n") != std::string::npos ||
                   filename.front() == ' ' || filename.back() == ' ';
  if (bad) throw DatasetError(path + ": cannot write image file name \"" + filename + "\"");
}

}  // namespace

std::vector<CameraFrame> ReadCameraCsv(const std::string& path, std::vector<int>* lines) {
  CsvReader reader(path, CameraColumns());
  TimestampOrder order;
  std::vector<CameraFrame> frames;
  while (reader.NextRow()) {
    CameraFrame frame;
    frame.t_ns = reader.Int64(0);
    order.Check(reader, frame.t_ns);
    frame.filename = std::string(reader.Field(1));
    if (frame.filename.empty()) reader.Fail("column 2 (filename): empty file name");
    frames.push_back(std::move(frame));
    if (lines != nullptr) lines->push_back(reader.line());
  }
  reader.RequireRows();
  return frames;
}

std::vector<CameraFrame> ReadCameraCsv(const std::string& path) {
  return ReadCameraCsv(path, nullptr);
}

void CheckImagesExist(const std::string& csv_path, const std::vector<CameraFrame>& frames,
                      const std::vector<int>& lines, const std::string& image_dir) {
  CHECK_EQ(frames.size(), lines.size());
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const std::string image = image_dir + "/" + frames[i].filename;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(image, ec)) {
      throw LineError(csv_path, lines[i], "listed image missing: " + image);
    }
  }
}

void WriteCameraCsv(const std::vector<CameraFrame>& frames, const std::string& path) {
  TextWriter out(path);
  out.Header(CameraColumns());
  for (const CameraFrame& frame : frames) {
    CheckWritableFilename(frame.filename, path);
    out.Int(frame.t_ns).Text(",").Text(frame.filename).Text("\n");
  }
  out.Save();
}

struct FeatureCsvStream::Reader {
  explicit Reader(const std::string& path) : csv(path, FeatureColumns()) {}

  // The next row into `pending`; false at the end.
  bool ReadRow() {
    pending.reset();
    if (!csv.NextRow()) return false;
    pending.emplace(ReadFeatureRow(csv), csv.line());
    order.Check(csv, pending->first.t_ns);
    return true;
  }

  CsvReader csv;
  TimestampOrder order{/*allow_equal=*/true};
  std::optional<std::pair<FeatureObservation, int>> pending;  ///< read, not yet returned (observation, line)
  std::vector<std::pair<FeatureObservation, int>> rows;
};

FeatureCsvStream::FeatureCsvStream(const std::string& path) : reader_(std::make_unique<Reader>(path)) {}

FeatureCsvStream::~FeatureCsvStream() = default;

bool FeatureCsvStream::Next(std::vector<FeatureObservation>* group) {
  group->clear();
  Reader& r = *reader_;
  if (!r.pending && !r.ReadRow()) return false;
  r.rows.clear();
  const Timestamp t_ns = r.pending->first.t_ns;
  do {
    r.rows.push_back(*r.pending);
  } while (r.ReadRow() && r.pending->first.t_ns == t_ns);
  // The simulator writes each frame's rows in this order already: then there is nothing to sort.
  const auto by_key = [](const auto& a, const auto& b) { return SortKey(a.first) < SortKey(b.first); };
  if (!std::is_sorted(r.rows.begin(), r.rows.end(), by_key)) std::stable_sort(r.rows.begin(), r.rows.end(), by_key);
  for (std::size_t i = 0; i < r.rows.size(); ++i) {
    if (i > 0 && SortKey(r.rows[i].first) == SortKey(r.rows[i - 1].first)) {
      throw LineError(r.csv.path(), r.rows[i].second,
                      "duplicated observation " + KeyText(r.rows[i].first) + " (also on line " +
                          std::to_string(r.rows[i - 1].second) + ")");
    }
    group->push_back(r.rows[i].first);
  }
  return true;
}

std::vector<FeatureObservation> ReadFeaturesCsv(const std::string& path) {
  FeatureCsvStream stream(path);
  std::vector<FeatureObservation> features, group;
  while (stream.Next(&group)) features.insert(features.end(), group.begin(), group.end());
  return features;
}

void WriteFeaturesCsv(const std::vector<FeatureObservation>& features, const std::string& path) {
  std::vector<FeatureObservation> sorted = features;
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const auto& a, const auto& b) { return SortKey(a) < SortKey(b); });
  TextWriter out(path);
  out.Header(FeatureColumns());
  for (std::size_t i = 0; i < sorted.size(); ++i) {
    const FeatureObservation& f = sorted[i];
    const bool duplicated = i > 0 && SortKey(f) == SortKey(sorted[i - 1]);
    if ((f.camera != 0 && f.camera != 1) || f.feature_id < 0 || duplicated) {
      throw DatasetError(path + ": cannot write observation " + KeyText(f) +
                         ": camera must be 0 or 1, feature_id >= 0, each key once");
    }
    out.Int(f.t_ns).Text(",").Int(f.camera).Text(",").Int(f.feature_id);
    out.Text(",").Double(f.uv_px.x()).Text(",").Double(f.uv_px.y()).Text("\n");
  }
  out.Save();
}

}  // namespace vio::tools
