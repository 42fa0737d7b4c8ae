#pragma once
/// @file edge_point.h
/// A point of a discontinuity edge seen from a point p, as the boundary term evaluates it
/// (docs/architecture.md §5 "Evaluation"): its direction from p, the Jacobian's linear form, and
/// whether it is visible. Shared by edge_jump_with (boundary_term.h) and crossing_jump
/// (crossing_jump.h).

#include "qsil/edgetree/edge_set.h"
#include "qsil/math.h"
#include "qsil/ray_tracer.h"

#include <optional>

namespace qsil {

/// The point at t of edge e seen from p (world, scene units): w0, w1 the edge's ends relative to p,
/// w_t = w0 + t (w1 - w0) the point relative to p, at distance dist along the unit direction w,
/// and n01 = w0 x w1 (the normal of the plane through p and the edge, the plus side of a jump).
struct EdgeSight {
  Vec3 w0, w1, wt, w, n01;
  double dist = 0;
  /// g = n01 / |w_t|^3: the Jacobian [QSS Eq. 3] is J = g . v_t for the point's velocity v_t
  /// relative to p.
  Vec3 jacobian_form() const { return n01 / (dist * dist * dist); }
};

/// The sight of edge e's point at t from p, or nothing when p is that point (distance 0).
inline std::optional<EdgeSight> edge_sight(const edgetree::ForestEdge& e, double t, const Vec3& p) {
  EdgeSight s;
  s.w0 = e.p0 - p;
  s.w1 = e.p1 - p;
  s.wt = s.w0 + t * (s.w1 - s.w0);
  s.dist = s.wt.norm();
  if (!(s.dist > 0)) return std::nullopt;
  s.w = s.wt / s.dist;
  s.n01 = s.w0.cross(s.w1);
  return s;
}

/// Whether `point` (world) is visible from `origin`: nothing but what `ignore` ignores is hit by
/// the ray from origin aimed at the point itself, which stops 1/4096 of the distance short of it
/// (the boundary term's visibility test, shared by edge_jump_with, crossing_jump and the primary
/// term's pieces). A point at the origin is visible.
inline bool point_visible(const RayTracer& tracer, const Vec3& origin, const Vec3& point, const IgnoreSet& ignore) {
  const Vec3 to = point - origin;
  const double dist = to.norm();
  if (!(dist > 0)) return true;
  return !tracer.occluded(origin, to / dist, dist * (1.0 - 1.0 / 4096.0), ignore);
}

}  // namespace qsil
