#include "vio/simulator/match_truth.h"

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

#include "vio/simulator/trajectory.h"

namespace vio::tools {
namespace {

/// Side of the cells anchors are hashed by for the missed-return search [m].
constexpr double kCellM = 0.05;
/// Views more oblique than this (cosine of the angle to the surface normal)
/// count as this oblique in a pixel's footprint.
constexpr double kMinCosIncidence = 0.1;
/// Farthest a missed-return candidate is searched from a new id's point [m].
constexpr double kMaxSearchM = 0.5;

// What a pixel of the rectified left image sees from the true camera.
struct Sight {
  Eigen::Vector3d p_w;     ///< the surface point [m]
  int surface = -1;        ///< scene.h numbering; -1: nothing hit
  double m_per_px = 0.0;   ///< the pixel's footprint on the surface there [m]
};

Sight See(const Scene& scene, const RectifiedStereo& stereo, const Eigen::Isometry3d& T_w_cl,
          const Eigen::Vector3d& z_px) {
  const Eigen::Vector3d ray_cl((z_px.x() - stereo.cx) / stereo.f, (z_px.z() - stereo.cy) / stereo.f, 1.0);
  const Eigen::Vector3d ray_w = (T_w_cl.linear() * ray_cl).normalized();
  const Scene::RayHit hit = scene.CastRay(T_w_cl.translation(), ray_w);
  Sight sight;
  if (hit.surface < 0) return sight;
  sight.surface = hit.surface;
  sight.p_w = T_w_cl.translation() + hit.t * ray_w;
  const int axis = (hit.surface % 6) / 2;  // faces are 2 * axis + side, per room and per box
  const double depth = hit.t / ray_cl.norm();
  sight.m_per_px = depth / stereo.f / std::max(std::abs(ray_w[axis]), kMinCosIncidence);
  return sight;
}

// Whether two sights are of one point: closer than max_error_px of the
// coarser footprint (on one surface or, at an edge, on two that meet there; a
// point hidden behind another is further away than that).
bool Same(const Sight& a, const Sight& b, double max_error_px) {
  return (a.p_w - b.p_w).norm() <= max_error_px * std::max(a.m_per_px, b.m_per_px);
}

/// A surface this much nearer than a point along the ray to it hides the point [m].
constexpr double kHiddenMarginM = 0.01;

// Whether `p_w`, seen from T_w_cl, is in front, projects within max_error_px
// of the rectified left pixel of z and is not hidden: at an edge a pixel's ray
// may pass the point and meet a surface far behind it.
bool Projects(const Scene& scene, const RectifiedStereo& stereo, const Eigen::Isometry3d& T_w_cl,
              const Eigen::Vector3d& p_w, const Eigen::Vector3d& z_px, double max_error_px) {
  const Eigen::Vector3d p_cl = T_w_cl.inverse() * p_w;
  if (p_cl.z() <= 0.0) return false;
  const double du = stereo.f * p_cl.x() / p_cl.z() + stereo.cx - z_px.x();
  const double dv = stereo.f * p_cl.y() / p_cl.z() + stereo.cy - z_px.z();
  if (std::hypot(du, dv) > max_error_px) return false;
  const Eigen::Vector3d to_point = p_w - T_w_cl.translation();
  const double distance = to_point.norm();
  const Scene::RayHit hit = scene.CastRay(T_w_cl.translation(), to_point / distance);
  return hit.surface >= 0 && hit.t >= distance - kHiddenMarginM;
}

struct IdState {
  Sight anchor;
  std::int64_t last_frame = 0;
};

// Anchors hashed by kCellM cells.
class AnchorGrid {
 public:
  void Insert(std::int64_t id, const Eigen::Vector3d& p_w) { cells_[Key(Cell(p_w))].push_back(id); }

  /// Whether pred(id) holds for some anchor within `radius_m` cells of p_w.
  template <class Pred>
  bool AnyNear(const Eigen::Vector3d& p_w, double radius_m, Pred pred) const {
    const Eigen::Vector3i c = Cell(p_w);
    const int r = static_cast<int>(std::ceil(radius_m / kCellM));
    for (int x = -r; x <= r; ++x) {
      for (int y = -r; y <= r; ++y) {
        for (int z = -r; z <= r; ++z) {
          const auto it = cells_.find(Key(c + Eigen::Vector3i(x, y, z)));
          if (it == cells_.end()) continue;
          for (std::int64_t id : it->second) {
            if (pred(id)) return true;
          }
        }
      }
    }
    return false;
  }

 private:
  static Eigen::Vector3i Cell(const Eigen::Vector3d& p_w) { return (p_w / kCellM).array().floor().cast<int>(); }
  static std::int64_t Key(const Eigen::Vector3i& c) {
    constexpr std::int64_t kSpan = 1 << 20;  // cells per axis: +-26 km at 5 cm
    return ((c.x() + kSpan / 2) * kSpan + (c.y() + kSpan / 2)) * kSpan + (c.z() + kSpan / 2);
  }
  std::unordered_map<std::int64_t, std::vector<std::int64_t>> cells_;
};

// Walks the frames once, keeping each id's anchor and last frame.
class Checker {
 public:
  Checker(const Scene& scene, const RectifiedStereo& stereo, double max_error_px)
      : scene_(scene), stereo_(stereo), max_error_px_(max_error_px) {}

  void Frame(std::int64_t k, const StereoFrame& frame, const std::optional<Eigen::Isometry3d>& T_w_b) {
    ++truth_.frames;
    std::unordered_set<std::int64_t> in_frame;
    for (const StereoObservation& obs : frame.observations) in_frame.insert(obs.landmark.value);
    for (const StereoObservation& obs : frame.observations) {
      ++truth_.observations;
      const auto it = ids_.find(obs.landmark.value);
      const Eigen::Isometry3d T_w_cl = T_w_b ? *T_w_b * stereo_.T_b_cl : Eigen::Isometry3d::Identity();
      const Sight sight = T_w_b ? See(scene_, stereo_, T_w_cl, obs.z_px) : Sight{};
      if (sight.surface < 0) {
        ++truth_.unchecked;
        if (it != ids_.end()) it->second.last_frame = k;
        continue;
      }
      if (it == ids_.end()) {
        NewId(k, obs, T_w_cl, sight, in_frame);
        continue;
      }
      MatchCounts& counts = it->second.last_frame == k - 1 ? truth_.continuing : truth_.reacquired;
      ++(Shows(T_w_cl, obs.z_px, sight, it->second.anchor) ? counts.correct : counts.wrong);
      it->second.last_frame = k;
    }
  }

  const MatchTruth& truth() const { return truth_; }

 private:
  // Whether the pixel of z, which sees `sight`, shows `anchor`.
  bool Shows(const Eigen::Isometry3d& T_w_cl, const Eigen::Vector3d& z_px, const Sight& sight,
             const Sight& anchor) const {
    return Same(sight, anchor, max_error_px_) ||
           Projects(scene_, stereo_, T_w_cl, anchor.p_w, z_px, max_error_px_);
  }

  void NewId(std::int64_t k, const StereoObservation& obs, const Eigen::Isometry3d& T_w_cl, const Sight& sight,
             const std::unordered_set<std::int64_t>& in_frame) {
    const LandmarkId id = obs.landmark;
    ++truth_.new_ids;
    const double radius_m = std::min(kMaxSearchM, max_error_px_ * std::max(sight.m_per_px, max_m_per_px_));
    const bool returned = grid_.AnyNear(sight.p_w, radius_m, [&](std::int64_t earlier) {
      const IdState& state = ids_.at(earlier);
      return state.last_frame < k - 1 && in_frame.count(earlier) == 0 && Shows(T_w_cl, obs.z_px, sight, state.anchor);
    });
    if (returned) ++truth_.missed_returns;
    ids_[id.value] = {sight, k};
    grid_.Insert(id.value, sight.p_w);
    max_m_per_px_ = std::max(max_m_per_px_, sight.m_per_px);
  }

  const Scene& scene_;
  const RectifiedStereo& stereo_;
  double max_error_px_;
  double max_m_per_px_ = 0.0;  ///< the coarsest anchor footprint so far [m]
  MatchTruth truth_;
  std::unordered_map<std::int64_t, IdState> ids_;
  AnchorGrid grid_;
};

double Ratio(std::int64_t numerator, std::int64_t denominator) {
  return denominator > 0 ? static_cast<double>(numerator) / static_cast<double>(denominator) : 0.0;
}

}  // namespace

double MatchTruth::ReacquisitionRate() const {
  return Ratio(reacquired.correct, reacquired.correct + missed_returns);
}

double MatchTruth::FalseReacquisitionRate() const { return Ratio(reacquired.wrong, reacquired.total()); }

MatchTruth CheckMatches(const Scene& scene, const RectifiedStereo& stereo,
                        const std::vector<GroundTruthState>& groundtruth, const std::vector<StereoFrame>& frames,
                        const MatchTruthOptions& options) {
  if (!(options.max_error_px > 0.0)) throw std::invalid_argument("match check: max_error_px must be > 0");
  Checker checker(scene, stereo, options.max_error_px);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    checker.Frame(static_cast<std::int64_t>(k), frames[k], InterpolatePose(groundtruth, frames[k].t_ns));
  }
  return checker.truth();
}

std::string MatchTruthJson(const MatchTruth& t) {
  auto counts = [](const MatchCounts& c) {
    return "{\"correct\": " + std::to_string(c.correct) + ", \"wrong\": " + std::to_string(c.wrong) + "}";
  };
  std::ostringstream os;
  os.precision(6);
  os << "{\"frames\": " << t.frames << ", \"observations\": " << t.observations << ", \"unchecked\": " << t.unchecked
     << ", \"new_ids\": " << t.new_ids << ", \"continuing\": " << counts(t.continuing)
     << ", \"continuing_wrong_fraction\": " << Ratio(t.continuing.wrong, t.continuing.total())
     << ", \"reacquired\": " << counts(t.reacquired) << ", \"missed_returns\": " << t.missed_returns
     << ", \"reacquisition_rate\": " << t.ReacquisitionRate()
     << ", \"false_reacquisition_rate\": " << t.FalseReacquisitionRate() << "}";
  return os.str();
}

}  // namespace vio::tools
