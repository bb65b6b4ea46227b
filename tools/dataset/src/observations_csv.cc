#include "vio/dataset/observations_csv.h"

#include <cmath>
#include <set>

#include "csv_reader.h"
#include "text_writer.h"

namespace vio::tools {
namespace {

const std::vector<std::string> kObservationsCsvColumns = {"timestamp [ns]", "landmark_id", "u_L [px]", "u_R [px]", "v [px]"};

}  // namespace

ObservationsCsvWriter::ObservationsCsvWriter(std::string path) : path_(std::move(path)), out_(path_) {
  if (!out_) throw DatasetError(path_ + ": cannot write");
  TextWriter header(path_);
  header.Header(kObservationsCsvColumns);
  out_ << header.text();
}

void ObservationsCsvWriter::Add(const StereoFrame& frame) {
  TextWriter rows(path_);
  for (const StereoObservation& obs : frame.observations) {
    rows.Int(frame.t_ns).Text(",").Int(obs.landmark.value);
    for (int k = 0; k < 3; ++k) rows.Text(",").Double(obs.z_px[k]);
    rows.Text("\n");
  }
  out_ << rows.text();
  if (!out_) throw DatasetError(path_ + ": cannot write");
}

void ObservationsCsvWriter::Close() {
  out_.close();
  if (!out_) throw DatasetError(path_ + ": cannot write");
}

std::vector<StereoFrame> ReadObservationsCsv(const std::string& path) {
  CsvReader reader(path, kObservationsCsvColumns);
  TimestampOrder order(/*allow_equal=*/true);
  std::vector<StereoFrame> frames;
  std::set<std::int64_t> ids_in_frame;
  while (reader.NextRow()) {
    const Timestamp t_ns = reader.Int64(0);
    order.Check(reader, t_ns);
    if (frames.empty() || frames.back().t_ns != t_ns) {
      frames.push_back(StereoFrame{t_ns, {}});
      ids_in_frame.clear();
    }
    const std::int64_t id = reader.Int64(1);
    if (!ids_in_frame.insert(id).second) reader.Fail("landmark " + std::to_string(id) + " twice in one frame");
    const Eigen::Vector3d z(reader.Double(2), reader.Double(3), reader.Double(4));
    frames.back().observations.push_back(StereoObservation{LandmarkId{id}, z});
  }
  return frames;
}

}  // namespace vio::tools
