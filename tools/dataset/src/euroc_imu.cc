// imu0/data.csv: one row per IMU sample,
//   #timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y,w_RS_S_z,a_RS_S_x [m s^-2],a_RS_S_y,a_RS_S_z
// timestamps strictly increasing; and the IMU timing check FindImuGaps.
#include <glog/logging.h>

#include <algorithm>

#include "csv_reader.h"
#include "euroc_internal.h"
#include "text_writer.h"
#include "vio/dataset/euroc_dataset.h"

namespace vio::tools {
namespace {

const std::vector<std::string>& ImuColumns() {
  static const std::vector<std::string> kColumns = {
      "timestamp [ns]",    "w_RS_S_x [rad s^-1]", "w_RS_S_y [rad s^-1]", "w_RS_S_z [rad s^-1]",
      "a_RS_S_x [m s^-2]", "a_RS_S_y [m s^-2]",   "a_RS_S_z [m s^-2]"};
  return kColumns;
}

// Readings beyond these are no IMU's (consumer and tactical IMUs saturate
// near 35 rad/s and 160 m/s^2; these leave room for shock sensors and unit
// mistakes): a corrupt row, rejected by line before it reaches the estimator.
constexpr double kMaxGyroRadS = 1e4;
constexpr double kMaxAccelMS2 = 1e6;

}  // namespace

std::vector<ImuSample> ReadImuCsv(const std::string& path, std::vector<int>* lines) {
  CsvReader reader(path, ImuColumns());
  TimestampOrder order;
  std::vector<ImuSample> imu;
  const std::string gyro_range = "any IMU's gyro range [rad/s]";
  const std::string accel_range = "any IMU's accelerometer range [m/s^2]";
  while (reader.NextRow()) {
    ImuSample sample;
    sample.t_ns = reader.Int64(0);
    order.Check(reader, sample.t_ns);
    for (int i = 0; i < 3; ++i) {
      sample.gyro_rad_s[i] = reader.BoundedDouble(1 + i, kMaxGyroRadS, gyro_range);
      sample.accel_m_s2[i] = reader.BoundedDouble(4 + i, kMaxAccelMS2, accel_range);
    }
    imu.push_back(sample);
    if (lines != nullptr) lines->push_back(reader.line());
  }
  reader.RequireRows();
  return imu;
}

std::vector<ImuSample> ReadImuCsv(const std::string& path) { return ReadImuCsv(path, nullptr); }

void WriteImuCsv(const std::vector<ImuSample>& imu, const std::string& path) {
  TextWriter out(path);
  out.Header(ImuColumns());
  for (const ImuSample& sample : imu) {
    out.Int(sample.t_ns);
    for (int i = 0; i < 3; ++i) out.Text(",").Double(sample.gyro_rad_s[i]);
    for (int i = 0; i < 3; ++i) out.Text(",").Double(sample.accel_m_s2[i]);
    out.Text("\n");
  }
  out.Save();
}

ImuGapReport FindImuGaps(const std::vector<ImuSample>& imu, double rate_hz) {
  CHECK_GT(rate_hz, 0.0) << "IMU rate must be positive";
  const double max_interval_ns = 3.0 * 1e9 / rate_hz;
  ImuGapReport report;
  for (std::size_t i = 1; i < imu.size(); ++i) {
    const Timestamp interval_ns = imu[i].t_ns - imu[i - 1].t_ns;
    if (static_cast<double>(interval_ns) > max_interval_ns) {
      ++report.count;
      report.longest_ns = std::max(report.longest_ns, interval_ns);
    }
  }
  return report;
}

}  // namespace vio::tools
