#pragma once
// Long-lived landmarks of the windowed policies (swf, msckf, fixed_lag): which
// landmarks stay parameters of the one cost after the states that observed
// them leave the window, and when they are marginalized after all.
//
// In the paper's terms: a windowed policy marginalizes a leaving state with
// the landmarks only it (swf: or it among others) ties together, or, in the
// MSCKF, marginalizes each used landmark at once. A kept landmark is left out
// of that marginalization: its observations from the leaving state go into
// the marginalization prior, which then involves the landmark (as with
// `ekf_landmarks=keep`), and a later observation with the same id is one more
// factor on the same variable (re-attachment). A kept landmark is
// marginalized (into the prior) when it was not observed for
// `persistent_retire_s`, or when keeping it would exceed the budget
// `persistent_landmarks`: the least useful go first, least useful = fewest
// observations, then oldest last observation, then larger id.
//
// This class is bookkeeping only (which ids are kept, when they were seen);
// the policies apply its decisions through Window::Marginalize.
#include <map>
#include <vector>

#include "vio/estimator/estimator_options.h"
#include "vio/estimator/types.h"

namespace vio {

class Window;

/// A landmark the policy is about to let go (marginalize), which may be kept instead.
struct PromotionCandidate {
  LandmarkId id;
  int observations = 0;        ///< observations of the landmark so far [count]
  Timestamp last_seen_ns = 0;  ///< its newest observation
};

/// What one frame's decision changes.
struct PersistentDecision {
  std::vector<LandmarkId> promoted;  ///< candidates kept from now on (id order)
  std::vector<LandmarkId> retired;   ///< kept landmarks to marginalize now (id order)
};

/// Cumulative counts.
struct PersistentCounts {
  int promoted = 0;         ///< landmarks kept beyond the window
  int returns = 0;          ///< re-observations of a kept landmark after at least one frame unseen
  int retired_unseen = 0;   ///< marginalized after persistent_retire_s without an observation
  int retired_budget = 0;   ///< marginalized to respect the budget
};

class PersistentLandmarks {
 public:
  explicit PersistentLandmarks(const PersistentOptions& options) : options_(options) {}

  bool enabled() const { return options_.persistent_landmarks > 0; }
  bool IsKept(LandmarkId id) const { return kept_.count(id) > 0; }
  int size() const { return static_cast<int>(kept_.size()); }
  const PersistentCounts& counts() const { return counts_; }

  /// Records the frame's observations of kept landmarks (they re-attach in
  /// the window by their id); call once per frame, before Decide.
  void Observe(const StereoFrame& frame);
  /// At frame time `now_ns`: kept landmarks unseen for persistent_retire_s
  /// retire; then candidates with at least persistent_min_track observations
  /// compete with the kept ones for the budget (most useful first).
  PersistentDecision Decide(Timestamp now_ns, const std::vector<PromotionCandidate>& candidates);
  /// Forgets a promoted landmark the policy could not add (no retirement).
  void Release(LandmarkId id) { kept_.erase(id); }
  /// Forgets the kept landmarks the window no longer has: a solve drops a landmark whose
  /// observations all failed at a rejected step's end point (Window::Solve), without retirement.
  void ForgetAbsent(const Window& window);

 private:
  struct Kept {
    int observations = 0;
    Timestamp last_seen_ns = 0;
  };

  PersistentOptions options_;
  std::map<LandmarkId, Kept> kept_;
  Timestamp last_frame_ns_ = 0;  ///< the frame of the last Observe
  PersistentCounts counts_;
};

/// Logs the counts (at the end of a run) when long-lived landmarks are on.
void LogPersistentCounts(const PersistentLandmarks& persistent);

/// The landmarks to marginalize with a leaving state, when `marginalizing`
/// is what the policy would marginalize without long-lived landmarks: kept
/// ones and newly promoted ones (observed at least persistent_min_track times
/// in the window) stay, retired ones are added; id order. `marginalizing`
/// itself when long-lived landmarks are off.
std::vector<LandmarkId> KeepLongLived(const std::vector<LandmarkId>& marginalizing, Timestamp now_ns,
                                      const Window& window, PersistentLandmarks& persistent);

}  // namespace vio
