#include "vio/estimator/stereo_motion.h"

#include <algorithm>
#include <optional>
#include <sstream>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/SVD>

#include "vio/estimator/so3.h"
#include "vio/estimator/stereo_geometry.h"

namespace vio {
namespace {

// One shared landmark: its stereo point in each body frame and the
// standard deviation of their difference (isotropic approximation of the
// stereo error: lateral z sigma / f, along the ray z^2 sigma / (f b)).
struct PointPair {
  Eigen::Vector3d p_a, p_b;
  double sigma = 1.0;
  Eigen::Vector3d z_a, z_b;  ///< the observations (u_L, u_R, v) [px]
};

// The covariance of the stereo point of z_px in the body: J J^T sigma^2, J the triangulation's
// Jacobian on (u_L, u_R, v) (its depth error along the ray).
Eigen::Matrix3d StereoPointCovariance(const Eigen::Vector3d& z_px, const RectifiedStereo& stereo, double pixel_sigma) {
  const double d = z_px.x() - z_px.y();
  const double z = stereo.f * stereo.baseline / d;
  const double xf = (z_px.x() - stereo.cx) / stereo.f, yf = (z_px.z() - stereo.cy) / stereo.f;
  Eigen::Matrix3d J;  // rows x, y, z; columns u_L, u_R, v
  J << z / stereo.f - xf * z / d, xf * z / d, 0, -yf * z / d, yf * z / d, z / stereo.f, -z / d, z / d, 0;
  const Eigen::Matrix3d R_b_c = stereo.T_b_cl.linear();
  return pixel_sigma * pixel_sigma * R_b_c * J * J.transpose() * R_b_c.transpose();
}

double StereoPointSigma(double depth_m, const RectifiedStereo& stereo, double pixel_sigma) {
  const double lateral = depth_m * pixel_sigma / stereo.f;
  const double along = depth_m * depth_m * pixel_sigma * std::sqrt(2.0) / (stereo.f * stereo.baseline);
  return std::sqrt(lateral * lateral + along * along);
}

// A landmark's stereo point in the left camera and the frame's (first) observation of it.
struct StereoPointInCamera {
  LandmarkId id;
  std::optional<Eigen::Vector3d> p_cl;  ///< none: no point within the depth limits
  Eigen::Vector3d z_px;
};

// The frame's stereo points in the left camera, in landmark id order; of an id observed more
// than once, the point of its last observation that has one, with its first observation.
std::vector<StereoPointInCamera> StereoPointsInCamera(const StereoFrame& frame, const RectifiedStereo& stereo,
                                              const ModelOptions& model) {
  std::vector<StereoPointInCamera> points;
  points.reserve(frame.observations.size());
  for (const StereoObservation& obs : frame.observations) {
    std::optional<Eigen::Vector3d> p_cl = TriangulateRectified(obs.z_px, stereo, model.min_disparity_px);
    if (p_cl && !(p_cl->z() <= model.max_depth_m)) p_cl.reset();
    points.push_back({obs.landmark, p_cl, obs.z_px});
  }
  const auto by_id = [](const StereoPointInCamera& a, const StereoPointInCamera& b) { return a.id < b.id; };
  if (!std::is_sorted(points.begin(), points.end(), by_id)) std::stable_sort(points.begin(), points.end(), by_id);
  size_t kept = 0;
  for (size_t k = 0; k < points.size(); ++k) {
    if (kept > 0 && points[kept - 1].id == points[k].id) {  // a repeated id keeps its first observation
      if (points[k].p_cl) points[kept - 1].p_cl = points[k].p_cl;
      continue;
    }
    points[kept++] = points[k];
  }
  points.resize(kept);
  points.erase(std::remove_if(points.begin(), points.end(), [](const StereoPointInCamera& p) { return !p.p_cl; }),
               points.end());
  return points;
}

std::vector<PointPair> SharedPoints(const StereoFrame& a, const StereoFrame& b, const RectifiedStereo& stereo,
                                    const ModelOptions& model) {
  const std::vector<StereoPointInCamera> in_a = StereoPointsInCamera(a, stereo, model);
  const std::vector<StereoPointInCamera> in_b = StereoPointsInCamera(b, stereo, model);
  std::vector<PointPair> pairs;
  auto it = in_b.begin();
  for (const StereoPointInCamera& point_a : in_a) {
    while (it != in_b.end() && it->id < point_a.id) ++it;
    if (it == in_b.end()) break;
    if (it->id != point_a.id) continue;
    const double sa = StereoPointSigma(point_a.p_cl->z(), stereo, model.pixel_sigma);
    const double sb = StereoPointSigma(it->p_cl->z(), stereo, model.pixel_sigma);
    pairs.push_back({stereo.T_b_cl * *point_a.p_cl, stereo.T_b_cl * *it->p_cl, std::sqrt(sa * sa + sb * sb),
                     point_a.z_px, it->z_px});
  }
  return pairs;
}

// Weighted least squares rigid fit p_a ~ R p_b + t over the kept pairs.
Eigen::Isometry3d FitRigid(const std::vector<PointPair>& pairs, const std::vector<bool>& keep) {
  Eigen::Vector3d ca = Eigen::Vector3d::Zero(), cb = Eigen::Vector3d::Zero();
  double total = 0;
  for (size_t i = 0; i < pairs.size(); ++i) {
    if (!keep[i]) continue;
    const double w = 1.0 / (pairs[i].sigma * pairs[i].sigma);
    ca += w * pairs[i].p_a;
    cb += w * pairs[i].p_b;
    total += w;
  }
  ca /= total;
  cb /= total;
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (size_t i = 0; i < pairs.size(); ++i) {
    if (keep[i]) H += (pairs[i].p_b - cb) * (pairs[i].p_a - ca).transpose() / (pairs[i].sigma * pairs[i].sigma);
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1.0 : 1.0;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = svd.matrixV() * D * svd.matrixU().transpose();
  T.translation() = ca - T.linear() * cb;
  return T;
}

// Keeps the pairs within max(5, 3 x median) whitened distance of the fit.
int RejectOutliers(const std::vector<PointPair>& pairs, const Eigen::Isometry3d& T, std::vector<bool>* keep) {
  std::vector<double> errors(pairs.size());
  for (size_t i = 0; i < pairs.size(); ++i) errors[i] = (pairs[i].p_a - T * pairs[i].p_b).norm() / pairs[i].sigma;
  std::vector<double> sorted = errors;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double bound = std::max(5.0, 3.0 * sorted[sorted.size() / 2]);
  int kept = 0;
  for (size_t i = 0; i < pairs.size(); ++i) {
    (*keep)[i] = errors[i] <= bound;
    kept += (*keep)[i];
  }
  return kept;
}

// The rigid fit with outlier rejection; nothing when fewer than min_landmarks are kept.
std::optional<StereoRelativePose> FitPairs(const std::vector<PointPair>& pairs, int min_landmarks,
                                           std::vector<bool>* keep) {
  if (static_cast<int>(pairs.size()) < std::max(3, min_landmarks)) return std::nullopt;
  keep->assign(pairs.size(), true);
  StereoRelativePose out;
  out.shared = static_cast<int>(pairs.size());
  out.T_a_b = FitRigid(pairs, *keep);
  for (int round = 0; round < 2; ++round) {
    out.inliers = RejectOutliers(pairs, out.T_a_b, keep);
    if (out.inliers < std::max(3, min_landmarks)) return std::nullopt;
    out.T_a_b = FitRigid(pairs, *keep);
  }
  return out;
}

// Gauss-Newton on r_i = p_a - (R p_b + t), weighted by (C_a + R C_b R^T)^-1; the perturbation
// R <- R Exp(dtheta), t <- t + dt.
Eigen::Isometry3d RefineWeighted(const std::vector<PointPair>& pairs, const std::vector<bool>& keep,
                                 const RectifiedStereo& stereo, double pixel_sigma, Eigen::Isometry3d T) {
  constexpr int kIterations = 5;
  std::vector<Eigen::Matrix3d> cov_a(pairs.size()), cov_b(pairs.size());
  for (size_t i = 0; i < pairs.size(); ++i) {
    if (!keep[i]) continue;
    cov_a[i] = StereoPointCovariance(pairs[i].z_a, stereo, pixel_sigma);
    cov_b[i] = StereoPointCovariance(pairs[i].z_b, stereo, pixel_sigma);
  }
  for (int iteration = 0; iteration < kIterations; ++iteration) {
    Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
    const Eigen::Matrix3d R = T.linear();
    for (size_t i = 0; i < pairs.size(); ++i) {
      if (!keep[i]) continue;
      const Eigen::Vector3d r = pairs[i].p_a - T * pairs[i].p_b;
      Eigen::Matrix<double, 3, 6> J;
      J << -Eigen::Matrix3d::Identity(), R * so3::Hat(pairs[i].p_b);
      const Eigen::Matrix3d W = (cov_a[i] + R * cov_b[i] * R.transpose()).inverse();
      H += J.transpose() * W * J;
      g += J.transpose() * W * r;
    }
    const Eigen::Matrix<double, 6, 1> step = -H.ldlt().solve(g);
    if (!step.allFinite()) break;
    T.translation() += step.head<3>();
    T.linear() = R * so3::Exp(step.tail<3>());
  }
  return T;
}

}  // namespace

std::optional<StereoRelativePose> RelativeStereoPose(const StereoFrame& a, const StereoFrame& b,
                                                     const RectifiedStereo& stereo, const ModelOptions& model,
                                                     int min_landmarks, int* shared) {
  const std::vector<PointPair> pairs = SharedPoints(a, b, stereo, model);
  if (shared != nullptr) *shared = static_cast<int>(pairs.size());
  std::vector<bool> keep;
  return FitPairs(pairs, min_landmarks, &keep);
}

std::optional<StereoRelativePose> WeightedRelativeStereoPose(const StereoFrame& a, const StereoFrame& b,
                                                             const RectifiedStereo& stereo, const ModelOptions& model,
                                                             int min_landmarks) {
  const std::vector<PointPair> pairs = SharedPoints(a, b, stereo, model);
  std::vector<bool> keep;
  std::optional<StereoRelativePose> out = FitPairs(pairs, min_landmarks, &keep);
  if (out) out->T_a_b = RefineWeighted(pairs, keep, stereo, model.pixel_sigma, out->T_a_b);
  return out;
}

StereoTrajectory ChainStereoPoses(const std::vector<StereoFrame>& frames, const RectifiedStereo& stereo,
                                  const ModelOptions& model, int min_landmarks) {
  StereoTrajectory out;
  if (frames.empty()) return out;
  out.T_0_k.push_back(Eigen::Isometry3d::Identity());
  for (size_t k = 1; k < frames.size(); ++k) {
    int shared = 0;
    const std::optional<StereoRelativePose> relative =
        RelativeStereoPose(frames[k - 1], frames[k], stereo, model, min_landmarks, &shared);
    if (!relative) {
      std::ostringstream why;
      why << "too few landmarks with stereo depth tracked from t=" << NanosToSeconds(frames[k - 1].t_ns)
          << " s to t=" << NanosToSeconds(frames[k].t_ns) << " s (" << shared << " shared, need "
          << min_landmarks << " consistent ones): no metric camera motion";
      out.failure = why.str();
      out.T_0_k.clear();
      return out;
    }
    out.T_0_k.push_back(out.T_0_k.back() * relative->T_a_b);
  }
  return out;
}

}  // namespace vio
