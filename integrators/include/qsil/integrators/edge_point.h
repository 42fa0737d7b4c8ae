#pragma once
/// @file edge_point.h
/// A point of a discontinuity edge seen from a point p, as the boundary term evaluates it
/// (docs/architecture.md §5 "Evaluation"): its direction from p, the Jacobian's linear form, and
/// whether it is visible; and the inputs of one evaluation there (OwnFace, EdgeJumpInputs). Shared
/// by edge_jump_with (boundary_term.h) and crossing_jump (crossing_jump.h).

#include "qsil/edgetree/edge_set.h"
#include "qsil/math.h"
#include "qsil/ray_tracer.h"

#include <optional>

namespace qsil {

/// The shading point's own triangle, for an edge that bounds it or otherwise lies in its plane
/// (face_in_plane; edge_jump_with).
///
/// p lies in the plane of its own triangle T (up to rounding), and so does every edge of T (and
/// every edge of a coplanar neighbour: a flat wall of several triangles): the
/// plane (p, edge) is T's plane, and the silhouette and crease predicates, which take the sign of
/// p against T's plane, are rounding noise there. What the integrand does across T's plane in the
/// directions toward the edge depends only on the other face T' of the edge:
/// - T' on the viewer's side of T's plane (a concave edge seen from the front): the directions
///   just on that side meet T' near the edge, those just beyond pass below T (the sliver rays of
///   docs/design-notes.md "Smooth shading", item 1) and see what lies beyond: a silhouette of T'
///   with foreground T' and that background;
/// - T' on the other side, in the plane, or no T' (a convex, flat or boundary edge): neither side
///   meets anything near the edge; the radiance is continuous there and the contribution is 0.
/// With face normals f_s cos vanishes in T's plane and so does the contribution anyway; with
/// smooth shading the shading normal tilts away from T's and it does not: treating these edges as
/// silhouettes made grad 60 % high for a vertex of a smooth bunny (docs/gradient-checks.md).
struct OwnFace {
  int face = -1;  ///< the edge's face in p's plane (face_in_plane: p's triangle when the edge bounds it), else -1
  Vec3 up = Vec3::Zero();  ///< T's unit geometric normal turned toward p's viewer (world); for a
                           ///< segment of an intersection curve always set at a path vertex (crossing_jump)
};

/// The two sides of a jump as the boundary term evaluated them (EdgeJumpInputs::sides): for each,
/// the radiance, its sign in the jump (jump = sign[0] L[0] + sign[1] L[1]) and the first hit of
/// its path (shape -1: the ray escaped). The primary term of attached camera hits
/// (attached_camera.h) weighs each side by its own film velocity. World coordinates.
struct EdgeSides {
  struct Side {
    Color L = Color::Zero();
    double sign = 0;
    Hit hit;  ///< u, v: barycentrics of the hit point on hit.triangle
  };
  int count = 0;  ///< sides recorded (2 after a non-zero jump)
  Side side[2];
  /// Records the radiance of the next side and its first hit (its sign is set by the jump).
  void record(const Color& L, const Hit& hit) {
    if (count < 2) side[count++] = Side{L, 0, hit};
  }
  /// Once both sides are recorded: the first side's sign is `first`, the second's minus it.
  void set_signs(double first) {
    if (count != 2) return;
    side[0].sign = first;
    side[1].sign = -first;
  }
};

/// The inputs of one evaluation of the boundary term's integrand at an edge point (edge_jump_with,
/// crossing_jump) that travel together: which point of which edge, seen from where, how its rays
/// start and pass back faces, the face rule for an edge in p's plane, and the path depth. World
/// coordinates, scene units. Read-only; the random numbers and the counters are passed beside it.
struct EdgeJumpInputs {
  const edgetree::Edge& edge;  ///< the sampled discontinuity edge (or segment of an intersection curve)
  double t = 0;                      ///< the edge point's parameter: edge.p0 + t (edge.p1 - edge.p0), t in [0, 1]
  Vec3 p = Vec3::Zero();             ///< the point the edge is seen from: a path vertex, or the camera centre
  /// The visibility ray's origin: p, or p offset off its surface (spawn_origin); for an edge in
  /// p's plane, p's offset origin below that plane (edge_jump_with, `own`).
  Vec3 vis_origin = Vec3::Zero();
  /// The direction from p to the edge point leaves p's surface on the side opposite to p's viewer
  /// (leaves_below): its rays pass through back faces. False for the camera.
  bool through_back_faces = false;
  OwnFace own;  ///< the edge's face in p's plane (face -1: none; always so for the camera)
  /// Segments of the path before p (trace_path's `segments`; 0 for the camera): the radiance
  /// paths started at the edge point continue with the remaining depth.
  int segments = 0;
  /// Or null: where the jump's evaluation records its two sides (EdgeSides), cleared first.
  EdgeSides* sides = nullptr;
};

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
inline std::optional<EdgeSight> edge_sight(const edgetree::Edge& e, double t, const Vec3& p) {
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
