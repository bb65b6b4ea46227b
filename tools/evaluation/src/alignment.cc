// Closed-form alignment of an estimated trajectory onto ground truth.
//
// With x_i the estimate positions, y_i the ground-truth positions, mu_x, mu_y
// their centroids and x~ = x - mu_x, y~ = y - mu_y, each mode minimises
//   sum_i |y_i - (s R x_i + t)|^2.
//
// se3 / sim3 (Umeyama 1991, Horn 1987):
//   Sigma = 1/n sum y~_i x~_i^T = U D V^T
//   S = diag(1, 1, -1) if det(U) det(V) < 0 else I          (no reflections)
//   R = U S V^T,   s = trace(D S) / (1/n sum |x~_i|^2) (sim3; else 1)
//   t = mu_y - s R mu_x
//
// posyaw (R = Rz(theta), s = 1): sum y~ . Rz x~ = cos(theta) sum (x~x y~x + x~y y~y)
//   + sin(theta) sum (x~x y~y - x~y y~x) + const, so
//   theta = atan2(sum (x~x y~y - x~y y~x), sum (x~x y~x + x~y y~y)),  t = mu_y - Rz mu_x.
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/SVD>

#include "vio/evaluation/trajectory_eval.h"

namespace vio::tools {
namespace {

struct CenteredPositions {
  Eigen::Vector3d mu_x = Eigen::Vector3d::Zero();  ///< estimate centroid
  Eigen::Vector3d mu_y = Eigen::Vector3d::Zero();  ///< ground-truth centroid
  Eigen::Matrix3Xd x;                              ///< estimate minus centroid
  Eigen::Matrix3Xd y;                              ///< ground truth minus centroid
};

CenteredPositions Center(const AssociatedTrajectory& trajectory) {
  const Eigen::Index n = static_cast<Eigen::Index>(trajectory.t_ns.size());
  CenteredPositions c;
  c.x.resize(3, n);
  c.y.resize(3, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    c.x.col(i) = trajectory.T_w_b_est[i].translation();
    c.y.col(i) = trajectory.T_w_b_gt[i].translation();
  }
  c.mu_x = c.x.rowwise().mean();
  c.mu_y = c.y.rowwise().mean();
  c.x.colwise() -= c.mu_x;
  c.y.colwise() -= c.mu_y;
  return c;
}

AlignmentResult FromRotationScale(const CenteredPositions& c, const Eigen::Matrix3d& R_gt_est,
                                  double scale) {
  AlignmentResult result;
  result.scale = scale;
  result.T_gt_est.linear() = R_gt_est;
  result.T_gt_est.translation() = c.mu_y - scale * R_gt_est * c.mu_x;
  return result;
}

AlignmentResult AlignUmeyama(const CenteredPositions& c, bool with_scale) {
  const double n = static_cast<double>(c.x.cols());
  const Eigen::Matrix3d sigma = c.y * c.x.transpose() / n;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(sigma, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d s_diag = Eigen::Vector3d::Ones();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) s_diag.z() = -1.0;
  const Eigen::Matrix3d R_gt_est = svd.matrixU() * s_diag.asDiagonal() * svd.matrixV().transpose();
  double scale = 1.0;
  if (with_scale) {
    const double variance_x = c.x.squaredNorm() / n;
    if (!(variance_x > 0.0)) {
      throw std::invalid_argument("sim3 alignment: the estimate positions do not move");
    }
    scale = svd.singularValues().dot(s_diag) / variance_x;
  }
  return FromRotationScale(c, R_gt_est, scale);
}

AlignmentResult AlignPosYaw(const CenteredPositions& c) {
  const Eigen::RowVectorXd cross =
      c.x.row(0).cwiseProduct(c.y.row(1)) - c.x.row(1).cwiseProduct(c.y.row(0));
  const Eigen::RowVectorXd dot =
      c.x.row(0).cwiseProduct(c.y.row(0)) + c.x.row(1).cwiseProduct(c.y.row(1));
  const double theta = std::atan2(cross.sum(), dot.sum());
  const Eigen::Matrix3d R_gt_est = Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return FromRotationScale(c, R_gt_est, 1.0);
}

size_t MinimumPoses(Alignment alignment) {
  switch (alignment) {
    case Alignment::kPosYaw: return 2;
    case Alignment::kSe3:
    case Alignment::kSim3: return 3;
    case Alignment::kNone: return 1;
  }
  return 1;
}

}  // namespace

Alignment ParseAlignment(const std::string& name) {
  for (Alignment a : {Alignment::kPosYaw, Alignment::kSe3, Alignment::kSim3, Alignment::kNone}) {
    if (name == AlignmentName(a)) return a;
  }
  throw std::invalid_argument("unknown alignment '" + name +
                              "' (expected one of: posyaw, se3, sim3, none)");
}

std::string AlignmentName(Alignment alignment) {
  switch (alignment) {
    case Alignment::kPosYaw: return "posyaw";
    case Alignment::kSe3: return "se3";
    case Alignment::kSim3: return "sim3";
    case Alignment::kNone: return "none";
  }
  return "unknown";
}

AlignmentResult Align(const AssociatedTrajectory& trajectory, Alignment alignment) {
  if (trajectory.t_ns.size() < MinimumPoses(alignment)) {
    std::ostringstream os;
    os << AlignmentName(alignment) << " alignment needs at least " << MinimumPoses(alignment)
       << " associated poses, got " << trajectory.t_ns.size();
    throw std::invalid_argument(os.str());
  }
  if (alignment == Alignment::kNone) return AlignmentResult{};
  const CenteredPositions centered = Center(trajectory);
  if (alignment == Alignment::kPosYaw) return AlignPosYaw(centered);
  return AlignUmeyama(centered, alignment == Alignment::kSim3);
}

AlignmentResult AlignAtFirstPose(const AssociatedTrajectory& trajectory, Alignment alignment) {
  if (trajectory.t_ns.empty()) throw std::invalid_argument("first-pose alignment needs an associated pose");
  AlignmentResult result;
  if (alignment == Alignment::kNone) return result;
  const Eigen::Isometry3d& est = trajectory.T_w_b_est.front();
  const Eigen::Isometry3d& gt = trajectory.T_w_b_gt.front();
  if (alignment == Alignment::kPosYaw) {
    // Swing-twist: q = swing * twist, twist = (w, 0, 0, z) normalized, the swing's axis is horizontal.
    const Eigen::Quaterniond q(Eigen::Matrix3d(gt.linear() * est.linear().transpose()));
    result.T_gt_est.linear() =
        Eigen::AngleAxisd(2.0 * std::atan2(q.z(), q.w()), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  } else {
    result.T_gt_est.linear() = gt.linear() * est.linear().transpose();
  }
  result.T_gt_est.translation() = gt.translation() - result.T_gt_est.linear() * est.translation();
  return result;
}

AssociatedTrajectory ApplyAlignment(const AssociatedTrajectory& trajectory,
                                    const AlignmentResult& alignment) {
  AssociatedTrajectory aligned = trajectory;
  for (Eigen::Isometry3d& T_w_b_est : aligned.T_w_b_est) {
    T_w_b_est.translation() *= alignment.scale;
    T_w_b_est = alignment.T_gt_est * T_w_b_est;
  }
  return aligned;
}

}  // namespace vio::tools
