#pragma once
/// @file crossing_jump.h
/// The radiance jump across a segment of an intersection curve (qsil/edgetree/intersection_curves.h)
/// seen from a point p: the boundary term's integrand at such a segment, for the secondary term
/// (p a path vertex) and the primary term (p the camera centre). docs/architecture.md §5
/// "Intersection curves".
///
/// Near a point x_e of the curve, triangles A and B cross along the line l of their planes, and
/// split space into four wedges. Seen from p (in one of them), the directions just on one side of
/// the plane Pi through p and l meet the half of A that bounds p's wedge (the half on p's side of
/// B's plane), those just on the other side the half of B on p's side of A's plane. So the jump is
/// the radiance leaving A at x_e minus that leaving B at x_e (each the limit from its visible half),
/// with the sign of the side of Pi each lies on: jump = L(minus side) - L(plus side), the plus side
/// being where w0 x w1 points (the convention of every edge of the boundary term, see
/// edge_jump_with).
///
/// Special cases:
/// - Sliver directions (`through_back_faces`: the direction from p leaves p's surface below its
///   geometric plane) pass through the back of one-sided surfaces: a half that turns its back to
///   p is then transparent, and that side sees what lies behind it (the other triangle's far half,
///   or, when that is transparent too, whatever the ray meets beyond x_e).
/// - p in the plane of A or B (p on one of the crossing triangles or a coplanar neighbour, e.g. a
///   floor made of two triangles): Pi is that plane, and both sides see the other triangle, Y:
///   above the plane (p's viewer side, `up`) its half there, below it (sliver directions, which
///   only a shading normal tilted past the geometric one reaches) its other half, seen from the
///   same side. The jump is between those two limits (e.g. the floor outside a sunk sphere and the
///   floor inside it, seen from a point of the sphere's band of crossing triangles). The rays run
///   parallel to the plane, a relative offset above and below it. Without `up` (the camera), 0.
/// - p on the curve's line (in both planes): 0.

#include "qsil/edgetree/edge_set.h"
#include "qsil/integrators/edge_point.h"
#include "qsil/integrators/path_tracer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>

namespace qsil {

/// Barycentrics (of vertices 1 and 2) of a point x in the plane of triangle `face` of `mesh`
/// (least squares in the plane), clamped into the triangle.
inline Vec2 barycentrics_in(const TriangleMesh& mesh, int face, const Vec3& x) {
  const Eigen::Vector3i& tri = mesh.triangles[size_t(face)];
  const Vec3 a = mesh.positions[size_t(tri[0])];
  const Vec3 e1 = mesh.positions[size_t(tri[1])] - a, e2 = mesh.positions[size_t(tri[2])] - a, r = x - a;
  const double d11 = e1.dot(e1), d12 = e1.dot(e2), d22 = e2.dot(e2), r1 = e1.dot(r), r2 = e2.dot(r);
  const double det = d11 * d22 - d12 * d12;
  double u = det != 0 ? (d22 * r1 - d12 * r2) / det : 0.0;
  double v = det != 0 ? (d11 * r2 - d12 * r1) / det : 0.0;
  if (!std::isfinite(u) || !std::isfinite(v)) u = v = 1.0 / 3.0;
  u = std::max(0.0, u);
  v = std::max(0.0, v);
  if (u + v > 1) {
    const double s = u + v;
    u /= s;
    v /= s;
  }
  return Vec2(u, v);
}

/// A segment of an intersection curve (e.crossing set) seen from p at its point x_e (crossing_jump;
/// world coordinates, scene units): the edge point's sight from p, and p against the planes of the
/// two crossing triangles A (0) and B (1).
struct CrossingSight {
  EdgeSight sight;                 ///< direction w and n01 = w0 x w1 from p (edge_sight)
  Vec3 xe = Vec3::Zero();          ///< the edge point x_e = p0 + t (p1 - p0)
  std::array<Vec3, 2> n;           ///< unit normals of A's and B's planes (CrossingSegment::plane)
  std::array<double, 2> height{};  ///< signed distance of p from A's and B's planes, along n
  /// p in A's or B's plane: |height| <= 2^-32 of the coordinates' magnitude (the tolerance of
  /// face_in_plane).
  std::array<bool, 2> in_plane{};
};

/// The rays of one crossing_jump evaluation: the radiance leaving a crossing triangle at x_e, what
/// lies beyond x_e, and visibility, each ray ignoring both crossing triangles and counted in
/// `stats`. References are to the caller's objects.
struct CrossingRays {
  const PathContext& ctx;
  const EdgeJumpInputs& in;  ///< the edge point (in.edge.crossing set) and p
  const CrossingSight& at;
  PathStats& stats;
  /// Rays leaving a limit point start inside the visible half by the offset of spawn_origin times
  /// this factor (crossing_reach).
  double reach = 1.0;

  const edgetree::CrossingSegment& crossing() const { return *in.edge.crossing; }

  /// The direction in triangle i's plane, perpendicular to the line, toward the side of the other
  /// triangle's plane with sign `toward` (+1: the side its normal points to). Not normalised.
  Vec3 half(int i, double toward) const {
    const std::array<Vec3, 2>& n = at.n;
    const Vec3 d = toward * (n[size_t(1 - i)] - n[size_t(1 - i)].dot(n[size_t(i)]) * n[size_t(i)]);
    return d;
  }
  /// Whether triangle i's surface is one-sided (no two-sided BSDF).
  bool one_sided(int i) const {
    const Scene& scene = *ctx.scene;
    const Shape& s = scene.shapes[size_t(crossing().shape[size_t(i)])];
    return !(s.bsdf >= 0 && s.bsdf < int(scene.bsdfs.size()) && scene.bsdfs[size_t(s.bsdf)].twosided);
  }
  /// Radiance leaving triangle i exactly at x_e toward p, the limit from its half `dir`.
  Color face_radiance(int i, const Vec3& dir, Sampler& rng) const {
    const edgetree::CrossingSegment& c = crossing();
    const Scene& scene = *ctx.scene;
    Hit h;
    h.shape = c.shape[size_t(i)];
    h.triangle = c.face[size_t(i)];
    const Vec2 uv = barycentrics_in(scene.shapes[size_t(h.shape)].mesh, h.triangle, at.xe);
    h.u = uv.x();
    h.v = uv.y();
    h.exact = true;
    const double len = dir.norm();
    h.inward = len > 0 ? Vec3(dir * (reach / len)) : Vec3::Zero();
    const PrimalView pv{&scene};
    const Color L(trace_path(ctx, pv, {in.p, at.sight.w, h, in.segments}, rng, stats));
    if (in.sides) in.sides->record(L, h);
    return L;
  }
  /// Both crossing triangles, for rays that pass back faces iff `through`.
  IgnoreSet ignore(bool through) const {
    IgnoreSet ig;
    ig.prims[0] = {crossing().shape[0], crossing().face[0]};
    ig.prims[1] = {crossing().shape[1], crossing().face[1]};
    ig.through_back_faces = through;
    return ig;
  }
  /// What a ray from `origin` along w meets beyond x_e (both triangles ignored).
  Color beyond(const Vec3& origin, bool through, Sampler& rng) const {
    ++stats.rays;
    const Hit h = ctx.tracer->intersect(origin, at.sight.w, kInf, ignore(through));
    const PrimalView pv{ctx.scene};
    const Color L(trace_path(ctx, pv, {origin, at.sight.w, h, in.segments}, rng, stats));
    if (in.sides) in.sides->record(L, h);
    return L;
  }
  /// point_visible, where the point is not the origin (a ray is traced and counted).
  bool visible(const Vec3& origin, const Vec3& target, bool through) const {
    if (!((target - origin).norm() > 0)) return false;
    ++stats.rays;
    return point_visible(*ctx.tracer, origin, target, ignore(through));
  }
};

/// The factor of CrossingRays::reach for planes with unit normals n: rays leaving a limit point
/// start inside the visible half by the offset of spawn_origin times it, so that the offset off
/// the face (along its normal) cannot carry them across the other plane: 1 + 2 |cos| / sin of the
/// angle between the planes, at most 64.
inline double crossing_reach(const std::array<Vec3, 2>& n) {
  const double sin_planes = n[0].cross(n[1]).norm(), cos_planes = std::abs(n[0].dot(n[1]));
  return std::clamp(1.0 + 2.0 * cos_planes / std::max(sin_planes, 1e-300), 1.0, 64.0);
}

/// The crossing seen from p (in.edge.crossing set), or nothing when p is the edge point.
inline std::optional<CrossingSight> crossing_sight(const EdgeJumpInputs& in) {
  const edgetree::Edge& e = in.edge;
  const edgetree::CrossingSegment& c = *e.crossing;
  const Vec3& p = in.p;
  const std::optional<EdgeSight> sight = edge_sight(e, in.t, p);
  if (!sight) return std::nullopt;
  CrossingSight at;
  at.sight = *sight;
  at.xe = e.p0 + in.t * (e.p1 - e.p0);
  at.n = {c.plane[0].head<3>(), c.plane[1].head<3>()};
  at.height = {at.n[0].dot(p) + c.plane[0][3], at.n[1].dot(p) + c.plane[1][3]};
  const double scale = std::max({p.cwiseAbs().maxCoeff(), e.p0.cwiseAbs().maxCoeff(), e.p1.cwiseAbs().maxCoeff()});
  at.in_plane = {std::abs(at.height[0]) <= 0x1p-32 * scale, std::abs(at.height[1]) <= 0x1p-32 * scale};
  return at;
}

/// The jump when p lies in the plane of triangle X (rays.at.in_plane[X]; see the file comment):
/// both sides see the other triangle, Y. Nothing (a zero contribution) when x_e is hidden.
inline std::optional<Color> in_plane_crossing_jump(const CrossingRays& rays, int X, Sampler& sampler) {
  const CrossingSight& at = rays.at;
  const Vec3& p = rays.in.p;
  const std::array<Vec3, 2>& n = at.n;
  // Common random numbers: both sides continue their paths with the same random numbers.
  Sampler same = sampler;
  const int Y = 1 - X;
  const Vec3 u = (rays.in.own.up.dot(n[size_t(X)]) >= 0 ? 1.0 : -1.0) * n[size_t(X)];  // p's viewer side of X's plane
  const Vec3& lo = rays.ctx.tracer->local_origin();
  const double offset =
      kRayOffsetRelative * std::max((p - lo).cwiseAbs().maxCoeff(), (at.xe - lo).cwiseAbs().maxCoeff());
  if (!rays.visible(p + offset * u, at.xe + offset * u, false)) return std::nullopt;
  const Vec3 dir_up = rays.half(Y, u.dot(n[size_t(X)]) > 0 ? 1.0 : -1.0);
  const bool y_transparent = rays.one_sided(Y) && at.height[size_t(Y)] < 0;  // below: sliver rays pass its back
  const Color L_up = rays.face_radiance(Y, dir_up, sampler);
  const Color L_down =
      y_transparent ? rays.beyond(at.xe - offset * u, true, same) : rays.face_radiance(Y, -dir_up, same);
  const double up_sign = at.sight.n01.dot(u) > 0 ? -1.0 : 1.0;
  if (rays.in.sides) rays.in.sides->set_signs(up_sign);
  return up_sign < 0 ? Color(L_down - L_up) : Color(L_up - L_down);
}

/// The jump in the general case (p in neither plane; see the file comment): A's visible half on
/// one side of Pi, B's on the other. Nothing (a zero contribution) when p is nearly on the line or
/// x_e is hidden.
inline std::optional<Color> general_crossing_jump(const CrossingRays& rays, Sampler& sampler) {
  const CrossingSight& at = rays.at;
  const bool through_back_faces = rays.in.through_back_faces;
  // Common random numbers: both sides continue their paths with the same random numbers.
  Sampler same = sampler;
  const double sA = at.height[0] > 0 ? 1.0 : -1.0, sB = at.height[1] > 0 ? 1.0 : -1.0;
  const Vec3 dirA = rays.half(0, sB), dirB = rays.half(1, sA);
  const double sideA = at.sight.n01.dot(dirA), sideB = at.sight.n01.dot(dirB);
  if (!(sideA * sideB < 0)) return std::nullopt;  // degenerate (p nearly on the line)
  if (!rays.visible(rays.in.vis_origin, at.xe, through_back_faces)) return std::nullopt;
  const std::array<double, 2> s{sA, sB};
  const std::array<Vec3, 2> dir{dirA, dirB};
  auto transparent = [&](int i) { return through_back_faces && rays.one_sided(i) && s[size_t(i)] < 0; };
  // The radiance on triangle i's side of Pi: its visible half, or, where a sliver ray passes
  // through its back, the other triangle's far half, or what lies beyond.
  auto side_radiance = [&](int i, Sampler& rng) {
    if (!transparent(i)) return rays.face_radiance(i, dir[size_t(i)], rng);
    if (!transparent(1 - i)) return rays.face_radiance(1 - i, Vec3(-dir[size_t(1 - i)]), rng);
    return rays.beyond(at.xe, true, rng);
  };
  const Color LA = side_radiance(0, sampler), LB = side_radiance(1, same);
  if (rays.in.sides) rays.in.sides->set_signs(sideA > 0 ? -1.0 : 1.0);
  return sideA > 0 ? Color(LB - LA) : Color(LA - LB);
}

/// The boundary term's integrand pieces at edge point `in` of a segment of an intersection curve
/// (in.edge.crossing set) seen from in.p: see the file comment, and edge_jump_with, whose contract
/// this follows (`in.vis_origin`, `in.through_back_faces`, `accept`; the jump returned, or nothing
/// for a zero contribution). `in.own.up`: p's geometric normal turned toward p's viewer (zero for
/// the camera), read only when p lies in the plane of one of the crossing triangles (|distance| <=
/// 2^-32 of the coordinates' magnitude, the tolerance of face_in_plane); in.own.face is not read.
template <class Accept>
std::optional<Color> crossing_jump(const PathContext& ctx, const EdgeJumpInputs& in, Sampler& sampler, PathStats& stats,
                                   Accept&& accept) {
  const std::optional<CrossingSight> at = crossing_sight(in);
  if (!at) return std::nullopt;
  if (at->in_plane[0] && at->in_plane[1]) return std::nullopt;  // p on the curve's line
  if ((at->in_plane[0] || at->in_plane[1]) && in.own.up == Vec3::Zero()) return std::nullopt;
  if (!accept(at->sight.jacobian_form())) return std::nullopt;
  const CrossingRays rays{.ctx = ctx, .in = in, .at = *at, .stats = stats, .reach = crossing_reach(at->n)};
  // ---- p in the plane of triangle X; both sides see the other triangle, Y.
  if (at->in_plane[0] || at->in_plane[1]) return in_plane_crossing_jump(rays, at->in_plane[0] ? 0 : 1, sampler);
  // ---- The general case: A's visible half on one side of Pi, B's on the other.
  return general_crossing_jump(rays, sampler);
}

}  // namespace qsil
