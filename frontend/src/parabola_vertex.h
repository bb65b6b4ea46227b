#pragma once
// Sub-pixel peak location shared by the front ends' correlation searches
// (private to the frontend library).

namespace vio::frontend::detail {

/// Offset of the vertex of the parabola through three equally spaced scores
/// (before, at, after) from the middle one, in sample steps; 0 when the
/// parabola does not open downward (no interior maximum).
inline double ParabolaVertex(float before, float at, float after) {
  const double curvature = static_cast<double>(before) - 2.0 * at + after;
  if (curvature >= 0.0) return 0.0;
  return 0.5 * (static_cast<double>(before) - after) / curvature;
}

}  // namespace vio::frontend::detail
