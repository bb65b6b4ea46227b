#pragma once
// The peak rules shared by the front ends' correlation (ZNCC) searches, the
// stereo row search and KLT re-identification (private to the frontend
// library): which templates are too flat to search with, when a second peak
// makes the best one ambiguous, and the best peak's sub-pixel position.

namespace vio::frontend::detail {

/// Templates with a smaller standard deviation are flat: not searched with [grey levels].
constexpr double kMinPatchStdGrey = 2.0;
/// A score further than kPeakHalfWidthPx from the best (in any direction)
/// that comes within kUniquenessMargin of it makes the best ambiguous [px], [ZNCC].
constexpr int kPeakHalfWidthPx = 2;
constexpr double kUniquenessMargin = 0.05;

/// Offset of the vertex of the parabola through three equally spaced scores
/// (before, at, after) from the middle one, in sample steps; 0 when the
/// parabola does not open downward (no interior maximum).
inline double ParabolaVertex(float before, float at, float after) {
  const double curvature = static_cast<double>(before) - 2.0 * at + after;
  if (curvature >= 0.0) return 0.0;
  return 0.5 * (static_cast<double>(before) - after) / curvature;
}

}  // namespace vio::frontend::detail
