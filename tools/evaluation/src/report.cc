// Text and JSON reports of a trajectory evaluation.
#include <cmath>
#include <iomanip>
#include <sstream>
#include <string>

#include "vio/evaluation/trajectory_eval.h"

namespace vio::tools {
namespace {

// A JSON number with 10 significant digits, or null for NaN / infinity.
std::string JsonNumber(double value) {
  if (!std::isfinite(value)) return "null";
  std::ostringstream os;
  os << std::setprecision(10) << value;
  return os.str();
}

template <class Vector>
std::string JsonArray(const Vector& v) {
  std::string out = "[";
  for (Eigen::Index i = 0; i < v.size(); ++i) out += (i ? ", " : "") + JsonNumber(v[i]);
  return out + "]";
}

std::string AlignmentJson(const TrajectoryEvaluation& e) {
  const Eigen::Quaterniond q_gt_est(e.alignment_result.T_gt_est.linear());
  std::ostringstream os;
  os << "\"alignment\": \"" << AlignmentName(e.alignment) << "\",\n"
     << "  \"T_gt_est\": {\"p_m\": " << JsonArray(e.alignment_result.T_gt_est.translation())
     << ", \"q_xyzw\": " << JsonArray(q_gt_est.coeffs()) << "},\n"
     << "  \"scale\": " << JsonNumber(e.alignment_result.scale);
  return os.str();
}

std::string AteJson(const AteResult& ate) {
  std::ostringstream os;
  os << "\"ate\": {\"rmse_m\": " << JsonNumber(ate.rmse_m) << ", \"mean_m\": " << JsonNumber(ate.mean_m)
     << ", \"median_m\": " << JsonNumber(ate.median_m) << ", \"max_m\": " << JsonNumber(ate.max_m)
     << ", \"rot_rmse_deg\": " << JsonNumber(ate.rot_rmse_deg) << ", \"num_poses\": " << ate.num_poses
     << ", \"num_skipped\": " << ate.num_skipped << "}";
  return os.str();
}

std::string RpeJson(const std::vector<RpeResult>& rpe) {
  std::ostringstream os;
  os << "\"rpe\": [";
  for (size_t k = 0; k < rpe.size(); ++k) {
    os << (k ? ",\n    " : "\n    ") << "{\"length_m\": " << JsonNumber(rpe[k].length_m)
       << ", \"trans_pct\": " << JsonNumber(rpe[k].trans_pct)
       << ", \"rot_deg_per_m\": " << JsonNumber(rpe[k].rot_deg_per_m)
       << ", \"num_pairs\": " << rpe[k].num_pairs << "}";
  }
  os << (rpe.empty() ? "]" : "\n  ]");
  return os.str();
}

// A fixed-point number, or "n/a" for NaN.
std::string Fixed(double value, int digits) {
  if (std::isnan(value)) return "n/a";
  std::ostringstream os;
  os << std::fixed << std::setprecision(digits) << value;
  return os.str();
}

}  // namespace

std::string ToJson(const TrajectoryEvaluation& evaluation) {
  return "{\n  " + AlignmentJson(evaluation) + ",\n  " + AteJson(evaluation.ate) + ",\n  " +
         RpeJson(evaluation.rpe) + "\n}";
}

std::string ToText(const TrajectoryEvaluation& e) {
  const AteResult& ate = e.ate;
  std::ostringstream os;
  os << "alignment   " << AlignmentName(e.alignment) << " (scale " << Fixed(e.alignment_result.scale, 6)
     << ")\n"
     << "poses       " << ate.num_poses << " compared with the ground truth"
     << (ate.num_skipped == 0 ? std::string(" (all)")
                              : ", " + std::to_string(ate.num_skipped) +
                                    " not (outside its time span or in a gap of it)")
     << "\n"
     << "ATE [m]     rmse " << Fixed(ate.rmse_m, 4) << "  mean " << Fixed(ate.mean_m, 4) << "  median "
     << Fixed(ate.median_m, 4) << "  max " << Fixed(ate.max_m, 4) << "\n"
     << "ATE rot     rmse " << Fixed(ate.rot_rmse_deg, 3) << " deg\n"
     << "RPE         length [m]  trans [%]  rot [deg/m]  pairs\n";
  for (const RpeResult& r : e.rpe) {
    os << "            " << std::setw(10) << Fixed(r.length_m, 1) << std::setw(11)
       << Fixed(r.trans_pct, 3) << std::setw(13) << Fixed(r.rot_deg_per_m, 4) << std::setw(7)
       << r.num_pairs << "\n";
  }
  return os.str();
}

}  // namespace vio::tools
