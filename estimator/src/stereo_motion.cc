#include "vio/estimator/stereo_motion.h"

#include <algorithm>
#include <map>
#include <sstream>

#include <Eigen/SVD>

#include "vio/estimator/stereo_geometry.h"

namespace vio {
namespace {

// One shared landmark: its stereo point in each body frame and the
// standard deviation of their difference (isotropic approximation of the
// stereo error: lateral z sigma / f, along the ray z^2 sigma / (f b)).
struct PointPair {
  Eigen::Vector3d p_a, p_b;
  double sigma = 1.0;
};

double StereoPointSigma(double depth_m, const RectifiedStereo& stereo, double pixel_sigma) {
  const double lateral = depth_m * pixel_sigma / stereo.f;
  const double along = depth_m * depth_m * pixel_sigma * std::sqrt(2.0) / (stereo.f * stereo.baseline);
  return std::sqrt(lateral * lateral + along * along);
}

std::map<LandmarkId, Eigen::Vector3d> StereoPointsInCamera(const StereoFrame& frame, const RectifiedStereo& stereo,
                                                           const ModelOptions& model) {
  std::map<LandmarkId, Eigen::Vector3d> points;
  for (const StereoObservation& obs : frame.observations) {
    const std::optional<Eigen::Vector3d> p_cl = TriangulateRectified(obs.z_px, stereo, model.min_disparity_px);
    if (p_cl && p_cl->z() <= model.max_depth_m) points[obs.landmark] = *p_cl;
  }
  return points;
}

std::vector<PointPair> SharedPoints(const StereoFrame& a, const StereoFrame& b, const RectifiedStereo& stereo,
                                    const ModelOptions& model) {
  const std::map<LandmarkId, Eigen::Vector3d> in_a = StereoPointsInCamera(a, stereo, model);
  const std::map<LandmarkId, Eigen::Vector3d> in_b = StereoPointsInCamera(b, stereo, model);
  std::vector<PointPair> pairs;
  for (const auto& [id, p_cl_a] : in_a) {
    const auto it = in_b.find(id);
    if (it == in_b.end()) continue;
    const double sa = StereoPointSigma(p_cl_a.z(), stereo, model.pixel_sigma);
    const double sb = StereoPointSigma(it->second.z(), stereo, model.pixel_sigma);
    pairs.push_back({stereo.T_b_cl * p_cl_a, stereo.T_b_cl * it->second, std::sqrt(sa * sa + sb * sb)});
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

}  // namespace

std::optional<StereoRelativePose> RelativeStereoPose(const StereoFrame& a, const StereoFrame& b,
                                                     const RectifiedStereo& stereo, const ModelOptions& model,
                                                     int min_landmarks, int* shared) {
  const std::vector<PointPair> pairs = SharedPoints(a, b, stereo, model);
  if (shared != nullptr) *shared = static_cast<int>(pairs.size());
  if (static_cast<int>(pairs.size()) < std::max(3, min_landmarks)) return std::nullopt;
  std::vector<bool> keep(pairs.size(), true);
  StereoRelativePose out;
  out.shared = static_cast<int>(pairs.size());
  out.T_a_b = FitRigid(pairs, keep);
  for (int round = 0; round < 2; ++round) {
    out.inliers = RejectOutliers(pairs, out.T_a_b, &keep);
    if (out.inliers < std::max(3, min_landmarks)) return std::nullopt;
    out.T_a_b = FitRigid(pairs, keep);
  }
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
