// Ground truth of the body (= IMU) frame in the world:
//  * state_groundtruth_estimate0/data.csv, 17 columns:
//      t [ns], p_w_b xyz [m], q_w_b w x y z, v_w_b xyz [m/s], gyro bias xyz [rad/s],
//      accel bias xyz [m/s^2]
//  * TUM text, space separated: t [s] x y z qx qy qz qw (velocity, biases zero).
// Quaternions are checked to be unit within kMaxQuaternionNormError and then
// normalised (left bit-exact when already unit, so write/read round-trips).
#include <cmath>

#include "csv_reader.h"
#include "text_writer.h"
#include "vio/dataset/euroc_dataset.h"

namespace vio::tools {
namespace {

/// Largest |norm - 1| of a quaternion in a file (EuRoC prints 6 decimals).
constexpr double kMaxQuaternionNormError = 1e-3;

const std::vector<std::string>& GroundTruthColumns() {
  static const std::vector<std::string> kColumns = {"timestamp",
                                                    "p_RS_R_x [m]",
                                                    "p_RS_R_y [m]",
                                                    "p_RS_R_z [m]",
                                                    "q_RS_w []",
                                                    "q_RS_x []",
                                                    "q_RS_y []",
                                                    "q_RS_z []",
                                                    "v_RS_R_x [m s^-1]",
                                                    "v_RS_R_y [m s^-1]",
                                                    "v_RS_R_z [m s^-1]",
                                                    "b_w_RS_S_x [rad s^-1]",
                                                    "b_w_RS_S_y [rad s^-1]",
                                                    "b_w_RS_S_z [rad s^-1]",
                                                    "b_a_RS_S_x [m s^-2]",
                                                    "b_a_RS_S_y [m s^-2]",
                                                    "b_a_RS_S_z [m s^-2]"};
  return kColumns;
}

const std::vector<std::string>& TumColumns() {
  static const std::vector<std::string> kColumns = {
      "timestamp [s]", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
  return kColumns;
}

Eigen::Vector3d ReadVector3(const CsvReader& reader, int first_column) {
  return {reader.Double(first_column), reader.Double(first_column + 1),
          reader.Double(first_column + 2)};
}

Eigen::Quaterniond ReadUnitQuaternion(const CsvReader& reader, int w_column, int x_column) {
  Eigen::Quaterniond q(reader.Double(w_column), reader.Double(x_column),
                       reader.Double(x_column + 1), reader.Double(x_column + 2));
  const double norm = q.norm();
  if (!(std::abs(norm - 1.0) <= kMaxQuaternionNormError)) {
    reader.Fail("quaternion norm " + std::to_string(norm) + " is not 1");
  }
  if (std::abs(q.squaredNorm() - 1.0) > 1e-14) q.normalize();
  return q;
}

void AppendVector3(TextWriter& out, const Eigen::Vector3d& v, const char* separator) {
  for (int i = 0; i < 3; ++i) out.Text(separator).Double(v[i]);
}

}  // namespace

std::vector<GroundTruthState> ReadGroundTruthCsv(const std::string& path) {
  CsvReader reader(path, GroundTruthColumns());
  TimestampOrder order;
  std::vector<GroundTruthState> gt;
  while (reader.NextRow()) {
    GroundTruthState state;
    state.t_ns = reader.Int64(0);
    order.Check(reader, state.t_ns);
    state.p_w_b = ReadVector3(reader, 1);
    state.q_w_b = ReadUnitQuaternion(reader, /*w_column=*/4, /*x_column=*/5);
    state.v_w_b = ReadVector3(reader, 8);
    state.gyro_bias = ReadVector3(reader, 11);
    state.accel_bias = ReadVector3(reader, 14);
    gt.push_back(state);
  }
  reader.RequireRows();
  return gt;
}

std::vector<GroundTruthState> ReadTumTrajectory(const std::string& path) {
  CsvReader reader(path, TumColumns(), CsvReader::Separator::kWhitespace);
  TimestampOrder order;
  std::vector<GroundTruthState> poses;
  while (reader.NextRow()) {
    GroundTruthState state;
    state.t_ns = reader.DecimalSeconds(0);
    order.Check(reader, state.t_ns);
    state.p_w_b = ReadVector3(reader, 1);
    state.q_w_b = ReadUnitQuaternion(reader, /*w_column=*/7, /*x_column=*/4);
    state.has_velocity_and_biases = false;
    poses.push_back(state);
  }
  reader.RequireRows();
  return poses;
}

void WriteGroundTruthCsv(const std::vector<GroundTruthState>& gt, const std::string& path) {
  TextWriter out(path);
  out.Header(GroundTruthColumns());
  for (const GroundTruthState& state : gt) {
    out.Int(state.t_ns);
    AppendVector3(out, state.p_w_b, ",");
    out.Text(",").Double(state.q_w_b.w());
    AppendVector3(out, state.q_w_b.vec(), ",");
    AppendVector3(out, state.v_w_b, ",");
    AppendVector3(out, state.gyro_bias, ",");
    AppendVector3(out, state.accel_bias, ",");
    out.Text("\n");
  }
  out.Save();
}

std::string TumTrajectoryLine(const GroundTruthState& pose, const std::string& path) {
  TextWriter out(path);
  out.DecimalSeconds(pose.t_ns);
  AppendVector3(out, pose.p_w_b, " ");
  AppendVector3(out, pose.q_w_b.vec(), " ");
  out.Text(" ").Double(pose.q_w_b.w()).Text("\n");
  return out.text();
}

void WriteTumTrajectory(const std::vector<GroundTruthState>& poses, const std::string& path) {
  TextWriter out(path);
  out.Text(kTumTrajectoryHeader);
  for (const GroundTruthState& state : poses) out.Text(TumTrajectoryLine(state, path));
  out.Save();
}

}  // namespace vio::tools
