#include "vio/estimator/persistent_landmarks.h"

#include <algorithm>
#include <tuple>

#include <glog/logging.h>

#include "vio/estimator/window.h"

namespace vio {

void PersistentLandmarks::Observe(const StereoFrame& frame) {
  for (const StereoObservation& obs : frame.observations) {
    auto it = kept_.find(obs.landmark);
    if (it == kept_.end()) continue;
    if (it->second.last_seen_ns < last_frame_ns_) ++counts_.returns;
    ++it->second.observations;
    it->second.last_seen_ns = frame.t_ns;
  }
  last_frame_ns_ = frame.t_ns;
}

PersistentDecision PersistentLandmarks::Decide(Timestamp now_ns, const std::vector<PromotionCandidate>& candidates) {
  PersistentDecision decision;
  const Timestamp retire_ns = SecondsToNanos(options_.persistent_retire_s);
  for (auto it = kept_.begin(); it != kept_.end();) {
    if (now_ns - it->second.last_seen_ns <= retire_ns) {
      ++it;
      continue;
    }
    decision.retired.push_back(it->first);
    ++counts_.retired_unseen;
    it = kept_.erase(it);
  }
  // Everything that may stay, most useful first: most observations, then
  // newest last observation, then smaller id.
  struct Entry {
    int observations;
    Timestamp last_seen_ns;
    LandmarkId id;
    bool candidate;
  };
  std::vector<Entry> entries;
  for (const auto& [id, kept] : kept_) entries.push_back({kept.observations, kept.last_seen_ns, id, false});
  for (const PromotionCandidate& c : candidates) {
    if (c.observations >= options_.persistent_min_track && !IsKept(c.id)) {
      entries.push_back({c.observations, c.last_seen_ns, c.id, true});
    }
  }
  std::sort(entries.begin(), entries.end(), [](const Entry& a, const Entry& b) {
    return std::make_tuple(-a.observations, -a.last_seen_ns, a.id.value) <
           std::make_tuple(-b.observations, -b.last_seen_ns, b.id.value);
  });
  const size_t budget = static_cast<size_t>(options_.persistent_landmarks);
  for (size_t i = 0; i < entries.size(); ++i) {
    const Entry& e = entries[i];
    if (i < budget && e.candidate) {
      kept_[e.id] = Kept{e.observations, e.last_seen_ns};
      decision.promoted.push_back(e.id);
      ++counts_.promoted;
    } else if (i >= budget && !e.candidate) {
      kept_.erase(e.id);
      decision.retired.push_back(e.id);
      ++counts_.retired_budget;
    }
  }
  std::sort(decision.promoted.begin(), decision.promoted.end());
  std::sort(decision.retired.begin(), decision.retired.end());
  return decision;
}

void PersistentLandmarks::ForgetAbsent(const Window& window) {
  for (auto it = kept_.begin(); it != kept_.end();) {
    it = window.HasLandmark(it->first) ? std::next(it) : kept_.erase(it);
  }
}

void LogPersistentCounts(const PersistentLandmarks& persistent) {
  if (!persistent.enabled()) return;
  const PersistentCounts& c = persistent.counts();
  LOG(INFO) << "long-lived landmarks: " << c.promoted << " promoted, " << c.returns << " re-observations after a gap, "
            << c.retired_unseen << " retired unseen, " << c.retired_budget << " retired over the budget, "
            << persistent.size() << " kept at the end";
}

std::vector<LandmarkId> KeepLongLived(const std::vector<LandmarkId>& marginalizing, Timestamp now_ns,
                                      const Window& window, PersistentLandmarks& persistent) {
  if (!persistent.enabled()) return marginalizing;
  persistent.ForgetAbsent(window);
  std::vector<PromotionCandidate> candidates;
  for (LandmarkId id : marginalizing) {
    const Landmark& landmark = window.landmark(id);
    if (persistent.IsKept(id) || landmark.observed_from.empty()) continue;
    const Timestamp last_seen_ns = window.state(*landmark.observed_from.rbegin()).t_ns;
    candidates.push_back({id, static_cast<int>(landmark.observed_from.size()), last_seen_ns});
  }
  const PersistentDecision decision = persistent.Decide(now_ns, candidates);
  std::vector<LandmarkId> out = decision.retired;
  for (LandmarkId id : marginalizing) {
    if (!persistent.IsKept(id)) out.push_back(id);
  }
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace vio
