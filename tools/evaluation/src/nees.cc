// NEES of an estimate with its reported covariance (nees.h).
#include "vio/evaluation/nees.h"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>

#include <Eigen/Cholesky>

#include "vio/dataset/euroc_dataset.h"
#include "vio/estimator/so3.h"

namespace vio::tools {
namespace {

constexpr int kUpperTriangle = 21;  // entries of a symmetric 6x6
constexpr int kSpeedBiasVariances = 9;

std::string Where(const std::string& path, int line) { return path + ":" + std::to_string(line); }

// The comma-separated numbers of one row, or why not.
std::vector<double> ParseRow(const std::string& text, const std::string& where, Timestamp* t_ns) {
  std::stringstream ss(text);
  std::string field;
  std::vector<double> values;
  bool first = true;
  while (std::getline(ss, field, ',')) {
    size_t used = 0;
    try {
      if (first) {
        *t_ns = std::stoll(field, &used);
      } else {
        values.push_back(std::stod(field, &used));
      }
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != field.size() || (!first && !std::isfinite(values.back()))) {
      throw DatasetError(where + ": '" + field + "' is not a " + (first ? "timestamp [ns]" : "finite number"));
    }
    first = false;
  }
  return values;
}

double Quadratic(const Eigen::VectorXd& e, const Eigen::MatrixXd& covariance) {
  return e.dot(covariance.llt().solve(e));
}

}  // namespace

std::vector<PoseCovariance> ReadCovarianceCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw DatasetError(path + ": cannot open the covariance file");
  std::vector<PoseCovariance> rows;
  std::string text;
  for (int line = 1; std::getline(in, text); ++line) {
    if (!text.empty() && text.back() == '\r') text.pop_back();
    if (text.empty() || text[0] == '#') continue;
    PoseCovariance row;
    const std::vector<double> values = ParseRow(text, Where(path, line), &row.t_ns);
    if (values.size() != kUpperTriangle + kSpeedBiasVariances) {
      throw DatasetError(Where(path, line) + ": " + std::to_string(values.size() + 1) + " columns, expected " +
                         std::to_string(1 + kUpperTriangle + kSpeedBiasVariances) +
                         " (t_ns, 21 pose covariance entries, 9 variances)");
    }
    if (!rows.empty() && row.t_ns <= rows.back().t_ns) {
      throw DatasetError(Where(path, line) + ": timestamp " + std::to_string(row.t_ns) +
                         " does not increase");
    }
    for (int r = 0, k = 0; r < 6; ++r) {
      for (int c = r; c < 6; ++c, ++k) row.pose(r, c) = row.pose(c, r) = values[static_cast<size_t>(k)];
    }
    if (row.pose.llt().info() != Eigen::Success) {
      throw DatasetError(Where(path, line) + ": the pose covariance is not positive definite");
    }
    rows.push_back(row);
  }
  return rows;
}

NeesResult ComputeNees(const AssociatedTrajectory& aligned, const AlignmentResult& alignment,
                       const std::vector<PoseCovariance>& covariances) {
  std::map<Timestamp, const PoseCovariance*> by_time;
  for (const PoseCovariance& c : covariances) by_time[c.t_ns] = &c;
  Eigen::Matrix<double, 6, 6> T = Eigen::Matrix<double, 6, 6>::Identity();
  T.topLeftCorner<3, 3>() = alignment.scale * alignment.T_gt_est.linear();
  NeesResult result;
  for (size_t i = 0; i < aligned.t_ns.size(); ++i) {
    const auto it = by_time.find(aligned.t_ns[i]);
    if (it == by_time.end()) {
      ++result.num_without_covariance;
      continue;
    }
    const Eigen::Matrix<double, 6, 6> sigma = T * it->second->pose * T.transpose();
    const Eigen::Isometry3d& est = aligned.T_w_b_est[i];
    const Eigen::Isometry3d& gt = aligned.T_w_b_gt[i];
    Eigen::Matrix<double, 6, 1> e;
    e.head<3>() = gt.translation() - est.translation();
    e.tail<3>() = so3::Log(Eigen::Matrix3d(est.linear().transpose() * gt.linear()));
    NeesSample sample;
    sample.t_ns = aligned.t_ns[i];
    sample.position = Quadratic(e.head<3>(), sigma.topLeftCorner<3, 3>());
    sample.orientation = Quadratic(e.tail<3>(), sigma.bottomRightCorner<3, 3>());
    sample.pose = Quadratic(e, sigma);
    result.samples.push_back(sample);
  }
  const double n = static_cast<double>(result.samples.size());
  for (const NeesSample& s : result.samples) {
    result.mean_position += s.position / n;
    result.mean_orientation += s.orientation / n;
    result.mean_pose += s.pose / n;
  }
  return result;
}

NeesResult EvaluateNees(const std::vector<GroundTruthState>& estimate,
                        const std::vector<GroundTruthState>& groundtruth,
                        const std::vector<PoseCovariance>& covariances, const EvaluationOptions& options) {
  const AssociatedTrajectory associated = Associate(estimate, groundtruth, options.association);
  const AlignmentResult alignment = AlignAtFirstPose(associated, options.alignment);
  return ComputeNees(ApplyAlignment(associated, alignment), alignment, covariances);
}

void WriteNeesCsv(const NeesResult& nees, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot open for writing");
  out << "#t_ns,nees_position,nees_orientation,nees_pose\n" << std::setprecision(8);
  for (const NeesSample& s : nees.samples) {
    out << s.t_ns << "," << s.position << "," << s.orientation << "," << s.pose << "\n";
  }
  if (!out) throw std::runtime_error(path + ": error writing");
}

std::string NeesJson(const NeesResult& nees) {
  std::ostringstream os;
  os << std::setprecision(8) << "{\"frames\": " << nees.samples.size();
  if (nees.samples.empty()) {
    os << ", \"position\": null, \"orientation\": null, \"pose\": null}";
  } else {
    os << ", \"position\": " << nees.mean_position << ", \"orientation\": " << nees.mean_orientation
       << ", \"pose\": " << nees.mean_pose << "}";
  }
  return os.str();
}

ChiSquareBounds AneesBounds95(int dof, int num_runs) {
  constexpr double kZ = 1.959963984540054;  // standard normal 97.5% quantile
  const double k = static_cast<double>(dof) * num_runs;
  const auto quantile = [k](double z) {
    const double a = 2.0 / (9.0 * k);
    return k * std::pow(1.0 - a + z * std::sqrt(a), 3);
  };
  return {quantile(-kZ) / num_runs, quantile(kZ) / num_runs};
}

}  // namespace vio::tools
