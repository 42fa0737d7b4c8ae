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
#include <cmath>

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

/// The boundary term's integrand pieces at point t of a segment of an intersection curve
/// (e.crossing set) seen from p: see the file comment, and edge_jump_with, whose contract this
/// follows (`vis_origin`, `through_back_faces`, `accept`, `jump`; the return value). `up`: p's
/// geometric normal turned toward p's viewer (zero for the camera), read only when p lies in the
/// plane of one of the crossing triangles (|distance| <= 2^-32 of the coordinates' magnitude, the
/// tolerance of face_in_plane).
template <class Accept>
bool crossing_jump(const PathContext& ctx, const edgetree::ForestEdge& e, double t, const Vec3& p,
                   const Vec3& vis_origin, bool through_back_faces, const Vec3& up, int seg, Sampler& sampler,
                   PathStats& stats, Color& jump, Accept&& accept) {
  const edgetree::CrossingSegment& c = *e.crossing;
  const Scene& scene = *ctx.scene;
  const std::optional<EdgeSight> sight = edge_sight(e, t, p);
  if (!sight) return false;
  const Vec3 &w = sight->w, &n01 = sight->n01;
  const Vec3 xe = e.p0 + t * (e.p1 - e.p0);
  const std::array<Vec3, 2> n{c.plane[0].head<3>(), c.plane[1].head<3>()};
  const std::array<double, 2> height{n[0].dot(p) + c.plane[0][3], n[1].dot(p) + c.plane[1][3]};
  const double scale = std::max({p.cwiseAbs().maxCoeff(), e.p0.cwiseAbs().maxCoeff(), e.p1.cwiseAbs().maxCoeff()});
  const std::array<bool, 2> in_plane{std::abs(height[0]) <= 0x1p-32 * scale, std::abs(height[1]) <= 0x1p-32 * scale};
  if (in_plane[0] && in_plane[1]) return false;  // p on the curve's line
  if ((in_plane[0] || in_plane[1]) && up == Vec3::Zero()) return false;
  if (!accept(sight->jacobian_form())) return false;

  // The direction in triangle i's plane, perpendicular to the line, toward the side of the other
  // triangle's plane with sign `toward` (+1: the side its normal points to).
  auto half = [&](int i, double toward) {
    const Vec3 d = toward * (n[size_t(1 - i)] - n[size_t(1 - i)].dot(n[size_t(i)]) * n[size_t(i)]);
    return d;
  };
  // Rays leaving a limit point start inside the visible half by the offset of spawn_origin times
  // this factor, so that the offset off the face (along its normal) cannot carry them across the
  // other plane: 1 + 2 |cos| / sin of the angle between the planes, at most 64.
  const double sin_planes = n[0].cross(n[1]).norm(), cos_planes = std::abs(n[0].dot(n[1]));
  const double reach = std::clamp(1.0 + 2.0 * cos_planes / std::max(sin_planes, 1e-300), 1.0, 64.0);
  auto one_sided = [&](int i) {
    const Shape& s = scene.shapes[size_t(c.shape[size_t(i)])];
    return !(s.bsdf >= 0 && s.bsdf < int(scene.bsdfs.size()) && scene.bsdfs[size_t(s.bsdf)].twosided);
  };
  const PrimalView pv{&scene};
  // Radiance leaving triangle i exactly at x_e toward p, the limit from its half `dir`.
  auto face_radiance = [&](int i, const Vec3& dir, Sampler& rng) {
    Hit h;
    h.shape = c.shape[size_t(i)];
    h.triangle = c.face[size_t(i)];
    const Vec2 uv = barycentrics_in(scene.shapes[size_t(h.shape)].mesh, h.triangle, xe);
    h.u = uv.x();
    h.v = uv.y();
    h.exact = true;
    const double len = dir.norm();
    h.inward = len > 0 ? Vec3(dir * (reach / len)) : Vec3::Zero();
    return Color(trace_path(ctx, pv, {p, w, h, seg}, rng, stats));
  };
  IgnoreSet ignore;
  ignore.prims[0] = {c.shape[0], c.face[0]};
  ignore.prims[1] = {c.shape[1], c.face[1]};
  // What a ray from `origin` along w meets beyond x_e (both triangles ignored).
  auto beyond = [&](const Vec3& origin, bool through, Sampler& rng) {
    IgnoreSet ig = ignore;
    ig.through_back_faces = through;
    ++stats.rays;
    const Hit h = ctx.tracer->intersect(origin, w, kInf, ig);
    return Color(trace_path(ctx, pv, {origin, w, h, seg}, rng, stats));
  };
  // point_visible, where the point is not the origin (a ray is traced and counted).
  auto visible = [&](const Vec3& origin, const Vec3& target, bool through) {
    if (!((target - origin).norm() > 0)) return false;
    IgnoreSet ig = ignore;
    ig.through_back_faces = through;
    ++stats.rays;
    return point_visible(*ctx.tracer, origin, target, ig);
  };
  // Common random numbers: both sides continue their paths with the same random numbers.
  Sampler same = sampler;

  if (in_plane[0] || in_plane[1]) {
    // ---- p in the plane of triangle X; both sides see the other triangle, Y.
    const int X = in_plane[0] ? 0 : 1, Y = 1 - X;
    const Vec3 u = (up.dot(n[size_t(X)]) >= 0 ? 1.0 : -1.0) * n[size_t(X)];  // p's viewer side of X's plane
    const Vec3& lo = ctx.tracer->local_origin();
    const double offset =
        kRayOffsetRelative * std::max((p - lo).cwiseAbs().maxCoeff(), (xe - lo).cwiseAbs().maxCoeff());
    if (!visible(p + offset * u, xe + offset * u, false)) return false;
    const Vec3 dir_up = half(Y, u.dot(n[size_t(X)]) > 0 ? 1.0 : -1.0);
    const bool y_transparent = one_sided(Y) && height[size_t(Y)] < 0;  // below: sliver rays pass its back
    const Color L_up = face_radiance(Y, dir_up, sampler);
    const Color L_down = y_transparent ? beyond(xe - offset * u, true, same) : face_radiance(Y, -dir_up, same);
    jump = n01.dot(u) > 0 ? Color(L_down - L_up) : Color(L_up - L_down);
    return true;
  }
  // ---- The general case: A's visible half on one side of Pi, B's on the other.
  const double sA = height[0] > 0 ? 1.0 : -1.0, sB = height[1] > 0 ? 1.0 : -1.0;
  const Vec3 dirA = half(0, sB), dirB = half(1, sA);
  const double sideA = n01.dot(dirA), sideB = n01.dot(dirB);
  if (!(sideA * sideB < 0)) return false;  // degenerate (p nearly on the line)
  if (!visible(vis_origin, xe, through_back_faces)) return false;
  const std::array<double, 2> s{sA, sB};
  const std::array<Vec3, 2> dir{dirA, dirB};
  auto transparent = [&](int i) { return through_back_faces && one_sided(i) && s[size_t(i)] < 0; };
  // The radiance on triangle i's side of Pi: its visible half, or, where a sliver ray passes
  // through its back, the other triangle's far half, or what lies beyond.
  auto side_radiance = [&](int i, Sampler& rng) {
    if (!transparent(i)) return face_radiance(i, dir[size_t(i)], rng);
    if (!transparent(1 - i)) return face_radiance(1 - i, Vec3(-dir[size_t(1 - i)]), rng);
    return beyond(xe, true, rng);
  };
  const Color LA = side_radiance(0, sampler), LB = side_radiance(1, same);
  jump = sideA > 0 ? Color(LB - LA) : Color(LA - LB);
  return true;
}

}  // namespace qsil
