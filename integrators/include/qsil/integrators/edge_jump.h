#pragma once
/// @file edge_jump.h
/// The jump of radiance across a sampled edge point seen from a shading point p and its Jacobian
/// [QSS Eq. 3, Appendix A; docs/architecture.md §5 "Evaluation"]. Evaluation of a sampled point
/// x_e = p + w_t with direction w = w_t/|w_t|:
/// Evaluation of a sampled point x_e = p + w_t with direction w = w_t/|w_t|:
/// - sign s = sign((w0 x w1).(x_opp - p)), x_opp the third vertex of a face of the edge: the side
///   of the plane through p and the edge on which the occluding faces lie;
/// - visibility: p -> x_e must be unoccluded (ignoring the edge's own faces), else 0; the ray
///   starts at p's offset ray origin and aims at x_e itself;
/// - foreground L_fg: radiance leaving the edge's face that faces p, at x_e, toward p (a path
///   started exactly there, with the remaining depth);
/// - background L_bg: radiance arriving at x_e along w from beyond the edge (a ray from x_e that
///   ignores the edge's two faces; an escaping ray sees the environment, never a dropped sample);
/// - contribution = T f_s(w, wo) s (L_bg - L_fg) J / pdf, for every parameter at once, added to
///   the derivative part of the path's radiance. T is the (detached) throughput to p: the
///   boundary term is already a first derivative.

#include "qsil/edgetree/edge_forest.h"
#include "qsil/edgetree/mesh_edges.h"
#include "qsil/integrators/crossing_jump.h"
#include "qsil/integrators/edge_point.h"
#include "qsil/integrators/geometry_view.h"
#include "qsil/integrators/path_tracer.h"

#include <optional>

namespace qsil {

/// The vertex of face `face` (one of edge `e`'s two faces) that is not on the edge (world).
inline const Vec3& opposite_vertex(const TriangleMesh& mesh, const edgetree::Edge& e, int face) {
  return mesh.positions[size_t(edgetree::opposite_vertex_index(mesh, e, face))];
}

/// The face of edge `e` that lies in the plane of p's triangle `triangle` (unit geometric normal
/// `ng`, p on it; world coordinates): `triangle` itself when the edge bounds it, else a face of the
/// edge whose three vertices lie in that plane up to rounding (|ng . (x - p)| <= 2^-32 of the
/// coordinates' magnitude: far above double rounding, far below any modelled feature), else -1.
/// Such an edge lies in p's plane as an edge of p's own triangle does (a flat region split into
/// several triangles: a box's wall, a floor quad), and is treated as OwnFace says.
inline int face_in_plane(const TriangleMesh& mesh, const edgetree::Edge& e, int triangle, const Vec3& ng,
                         const Vec3& p) {
  if (e.f0 == triangle || e.f1 == triangle) return triangle;
  auto in_plane = [&](const Vec3& x) {
    return std::abs(ng.dot(x - p)) <= 0x1p-32 * (x.cwiseAbs().maxCoeff() + p.cwiseAbs().maxCoeff());
  };
  if (!in_plane(e.p0) || !in_plane(e.p1)) return -1;  // the edge itself leaves the plane
  for (int face : {e.f0, e.f1})
    if (face >= 0 && in_plane(opposite_vertex(mesh, e, face))) return face;
  return -1;
}

/// The inputs of edge point (e, t) seen from path vertex `si` (world; `wo_world` the unit direction
/// toward its viewer, `w` the unit direction from si.p to the edge point) after `segments`
/// segments: the edge's face in si's plane (OwnFace: for an edge of si's shape in that plane,
/// face_in_plane and the viewer's side; for a segment of an intersection curve the viewer's side
/// alone, crossing_jump), the visibility ray's origin (below that plane for such an edge,
/// edge_jump_with) and whether its rays pass back faces (leaves_below). Shared by the per-vertex
/// boundary term (boundary_term.h) and projective sampling (integrators/projective_boundary.h).
template <class T>
EdgeJumpInputs vertex_edge_inputs(const PathContext& ctx, const edgetree::Edge& e, double t,
                                  const SurfaceInteraction<T>& si, const Vec3& wo_world, const Vec3& w, int segments) {
  const Vec3 p = value(si.p), ng = value(si.ng);
  const Vec3 up = ng.dot(wo_world) < 0 ? Vec3(-ng) : ng;
  OwnFace own;
  if (e.crossing) {
    own.up = up;  // crossing_jump
  } else if (e.shape == si.shape) {
    own.face = face_in_plane(ctx.scene->shapes[size_t(e.shape)].mesh, e, si.triangle, ng, p);
    if (own.face >= 0) own.up = up;
  }
  // An edge in p's plane takes its rays below that plane (edge_jump_with): its origin there.
  return EdgeJumpInputs{.edge = e,
                        .t = t,
                        .p = p,
                        .vis_origin = spawn_origin(si, own.face >= 0 ? Vec3(-own.up) : w),
                        .through_back_faces = leaves_below(si, wo_world, w),
                        .own = own,
                        .segments = segments};
}

/// The rays of the boundary term ignore the sampled edge's own two faces (an Embree filter on
/// their primitive ids: no absolute epsilon). `through_back_faces` as for every ray of the path
/// tracer (leaves_below).
inline IgnoreSet edge_faces(const edgetree::Edge& e, bool through_back_faces) {
  IgnoreSet ignore;
  if (e.crossing) {  // a segment of an intersection curve: its two crossing triangles
    ignore.prims[0] = {e.crossing->shape[0], e.crossing->face[0]};
    ignore.prims[1] = {e.crossing->shape[1], e.crossing->face[1]};
    ignore.through_back_faces = through_back_faces;
    return ignore;
  }
  ignore.prims[0] = {e.shape, e.f0};
  ignore.prims[1] = {e.f1 >= 0 ? e.shape : -1, e.f1};
  ignore.through_back_faces = through_back_faces;
  return ignore;
}

/// How the rays of the boundary term run for a non-crossing edge point (edge_jump_with): the ray
/// filter and, for an edge in p's plane (OwnFace), the other face and the offset below that plane.
struct EdgeRays {
  IgnoreSet ignore;           ///< edge_faces; through back faces for an edge in p's plane
  int own_occluder = -1;      ///< for an edge in p's plane: the other face, when it occludes; else -1
  Vec3 below = Vec3::Zero();  ///< for an edge in p's plane: the offset of its rays below that plane (world)
};

/// The rays of edge point `in` (not a crossing; `mesh` its shape's mesh), or nothing for a zero
/// contribution: an edge in p's plane whose other face T' is missing, below p's plane or in it.
inline std::optional<EdgeRays> edge_rays(const PathContext& ctx, const EdgeJumpInputs& in, const TriangleMesh& mesh) {
  const edgetree::Edge& e = in.edge;
  const Vec3& p = in.p;
  const OwnFace& own = in.own;
  EdgeRays rays;
  rays.ignore = edge_faces(e, in.through_back_faces);
  if (own.face >= 0) {
    // ---- An edge in p's plane (OwnFace): a silhouette of the other face T' when T' lies on the
    // viewer's side of p's plane; beyond the edge on the far side of that plane the background is
    // a sliver ray. Its rays (visibility and background) run parallel to p's plane, just below
    // it, on the sliver rays' side (through back faces, as they do): in the plane itself they
    // would lie in the plane of p's triangle and its coplanar neighbours, where Embree's test is
    // degenerate and meets one of them at random (open-box-point under a constant sky: ~24 % of
    // the background rays and ~1 % of the visibility rays near a corner of the wall, the own
    // edges' term 23-29 % short). The offset is vis_origin's (below p's plane, from p's triangle),
    // or larger where the edge's coordinates ask for more.
    rays.own_occluder = e.f0 == own.face ? e.f1 : e.f0;
    if (rays.own_occluder < 0) return std::nullopt;
    if (!((opposite_vertex(mesh, e, rays.own_occluder) - p).dot(own.up) > 0))
      return std::nullopt;  // T' below p's plane or in it
    rays.ignore.through_back_faces = true;
    const Vec3& c = ctx.tracer->local_origin();
    const double edge_scale = std::max((e.p0 - c).cwiseAbs().maxCoeff(), (e.p1 - c).cwiseAbs().maxCoeff());
    rays.below = -std::max((p - in.vis_origin).dot(own.up), kRayOffsetRelative * edge_scale) * own.up;
  }
  return rays;
}

/// The side of the plane (p, edge) on which face `face` of the edge lies: the sign of
/// (w0 x w1).(x_opp - p) for the face's third vertex x_opp (n01 = w0 x w1, EdgeSight; world).
inline double plane_side(const Vec3& n01, const TriangleMesh& mesh, const edgetree::Edge& e, int face,
                         const Vec3& p) {
  return n01.dot(opposite_vertex(mesh, e, face) - p);
}

/// Radiance leaving face `face` of edge point `in`'s edge (not a crossing) exactly at the edge
/// point toward p, along the unit direction w from p, continued with the remaining depth and the
/// random numbers of `rng`. The point is known: barycentrics (1-t at v0, t at v1) in the face's
/// vertex order (the face may be seen edge-on from p, where a ray-plane intersection degenerates).
/// Recorded in in.sides when set.
inline Color edge_face_radiance(const PathContext& ctx, const EdgeJumpInputs& in, const Vec3& w, int face, Sampler& rng,
                                PathStats& stats) {
  const edgetree::Edge& e = in.edge;
  const double t = in.t;
  const PrimalView pv{ctx.scene};
  Hit h;
  h.shape = e.shape;
  h.triangle = face;
  const Eigen::Vector3i& tri = ctx.scene->shapes[e.shape].mesh.triangles[face];
  auto weight = [&](int k) { return tri[k] == e.v0 ? 1.0 - t : (tri[k] == e.v1 ? t : 0.0); };
  h.u = weight(1);
  h.v = weight(2);
  h.exact = true;
  const Color L(trace_path(ctx, pv, {in.p, w, h, in.segments}, rng, stats));
  if (in.sides) in.sides->record(L, h);
  return L;
}

/// The jump across a crease (edgetree::CreaseSet; both faces facing p) at edge point `in` seen
/// along `sight`: the two faces lie on opposite sides of the plane (p, edge); the radiance jumps
/// from one face's to the other's. Reynolds transport: jump = L(side -) - L(side +), + the side
/// (w0 x w1) points to. Nothing (a zero contribution) when the first face lies in that plane.
inline std::optional<Color> crease_jump(const PathContext& ctx, const EdgeJumpInputs& in, const EdgeSight& sight,
                                        Sampler& sampler, PathStats& stats) {
  const edgetree::Edge& e = in.edge;
  const double s0 = plane_side(sight.n01, ctx.scene->shapes[e.shape].mesh, e, e.f0, in.p);
  if (s0 == 0) return std::nullopt;
  // Common random numbers: both faces continue their paths with the same random numbers, so
  // the difference is the jump itself (where the two paths differ), not two independent noises.
  Sampler same = sampler;
  const Color L0 = edge_face_radiance(ctx, in, sight.w, e.f0, sampler, stats),
              L1 = edge_face_radiance(ctx, in, sight.w, e.f1, same, stats);
  if (in.sides) in.sides->set_signs(s0 > 0 ? -1.0 : 1.0);
  return s0 > 0 ? Color(L1 - L0) : Color(L0 - L1);
}

/// The jump across a silhouette or boundary edge (or an edge in p's plane, rays.own_occluder set)
/// at edge point `in` seen along `sight`: s (L_bg - L_fg), both faces on the occluder's side s.
/// Nothing (a zero contribution) when the occluding face lies in the plane (p, edge).
inline std::optional<Color> silhouette_jump(const PathContext& ctx, const EdgeJumpInputs& in, const EdgeSight& sight,
                                            const EdgeRays& rays, Sampler& sampler, PathStats& stats) {
  const edgetree::Edge& e = in.edge;
  const Vec3& p = in.p;
  const int own_occluder = rays.own_occluder;
  const double side =
      plane_side(sight.n01, ctx.scene->shapes[e.shape].mesh, e, own_occluder >= 0 ? own_occluder : e.f0, p);
  if (side == 0) return std::nullopt;
  const double s = side > 0 ? 1.0 : -1.0;
  // Foreground: the face that faces p. Background: beyond the edge along the same direction
  // (escaping rays see the environment).
  const Vec4 x(p.x(), p.y(), p.z(), 1.0);
  const int face = own_occluder >= 0 ? own_occluder : ((e.f1 < 0 || e.q0.dot(x) > 0) ? e.f0 : e.f1);
  const Color L_fg = edge_face_radiance(ctx, in, sight.w, face, sampler, stats);
  // The background ray starts at the edge point (for an edge in p's plane, below it: see
  // edge_rays).
  const Vec3 xe = p + sight.wt;
  const Vec3 bg_origin = xe + rays.below;
  ++stats.rays;
  const Hit bg = ctx.tracer->intersect(bg_origin, sight.w, kInf, rays.ignore);
  const PrimalView pv{ctx.scene};
  const Color L_bg = trace_path(ctx, pv, {bg_origin, sight.w, bg, in.segments}, sampler, stats);
  if (in.sides) {
    in.sides->record(L_bg, bg);
    in.sides->set_signs(-s);  // the first side: the foreground, recorded by edge_face_radiance
  }
  return Color(s * (L_bg - L_fg));
}

/// The radiance jump and the Jacobian at a point of a discontinuity edge seen from p (shared by
/// the secondary and the primary boundary terms), for edge point `in` (EdgeJumpInputs), drawing
/// from `sampler` and counting rays in `stats`. On success (returns the jump):
/// - jump = s (L_bg - L_fg): the occluder-side sign times background minus foreground radiance
///   for a silhouette or boundary edge; for a crease (edgetree::CreaseSet; an edge whose two
///   faces both face p), the radiance on the minus side minus that on the plus side of the plane
///   (p, edge), the plus side being where w0 x w1 points, both with the same random numbers;
/// - the Jacobian J = det(w0, w1, v_t) / |w_t|^3 = g . v_t (per unit t), v_t the edge point's
///   velocity relative to p, through `accept` (below; edge_jump computes J per parameter).
/// Returns nothing for a zero contribution: p on the edge's line, no relative velocity, or the edge
/// point hidden from p. `in.vis_origin` starts the visibility ray (p, offset off its surface), which
/// aims at the edge point from there (not along w) and stops 1/4096 of the distance short of it.
/// `in.through_back_faces`: the direction from p to the edge point leaves p's surface on the side
/// opposite to p's viewer (leaves_below), so that ray and its continuation beyond the edge pass
/// through back faces, as every such ray of the path tracer does.
///
/// `in.own`: the edge's face in p's plane (OwnFace, face_in_plane; face -1 otherwise, and for the
/// camera): then the plane (p, edge) is p's triangle's plane and the edge is treated as
/// OwnFace says, not by the silhouette or crease rule; its visibility and background rays run
/// parallel to that plane just below it (on the side opposite own.up), vis_origin must be p's
/// offset origin on that side (spawn_origin toward -own.up), and through_back_faces is taken as
/// true for them.
///
/// `accept(g)` receives g = (w0 x w1) / |w_t|^3, the Jacobian's linear form in the relative
/// velocity (J = g . v_t), before any ray is traced or random number drawn; returning false ends
/// the evaluation with a zero contribution (edge_jump: no relative velocity). Reverse mode
/// (integrators/reverse.cpp) keeps g itself: the adjoint of v_t.
///
/// A segment of an intersection curve (e.crossing) is evaluated by crossing_jump, with own.up.
template <class Accept>
std::optional<Color> edge_jump_with(const PathContext& ctx, const EdgeJumpInputs& in, Sampler& sampler,
                                    PathStats& stats, Accept&& accept) {
  const edgetree::Edge& e = in.edge;
  if (in.sides) *in.sides = EdgeSides{};
  if (e.crossing) return crossing_jump(ctx, in, sampler, stats, accept);
  const Vec3& p = in.p;
  const std::optional<EdgeSight> sight = edge_sight(e, in.t, p);
  if (!sight) return std::nullopt;
  if (!accept(sight->jacobian_form())) return std::nullopt;
  const std::optional<EdgeRays> rays = edge_rays(ctx, in, ctx.scene->shapes[e.shape].mesh);
  if (!rays) return std::nullopt;
  // ---- Visibility of the edge point from p (ignoring the edge's own faces).
  // The ray aims from vis_origin at the edge point itself. Along w, from an origin offset off
  // p's surface, it would pass the edge point at the offset's distance (2^-20 of the coordinate
  // magnitude: 0.01 for a unit-size object 1e4 from the origin), inside the occluder's outline
  // for about half of the grazing directions, and meet the faces next to the edge. For an edge
  // in p's plane, from p + below at the edge point + below.
  const Vec3 edge_point = e.p0 + in.t * (e.p1 - e.p0);
  const Vec3 origin = rays->own_occluder >= 0 ? Vec3(p + rays->below) : in.vis_origin;
  if (!((edge_point + rays->below - origin).norm() > 0)) return std::nullopt;
  ++stats.rays;
  if (!point_visible(*ctx.tracer, origin, edge_point + rays->below, rays->ignore)) return std::nullopt;
  if (rays->own_occluder < 0 && e.crease && !edgetree::edge_is_silhouette(e, p))
    return crease_jump(ctx, in, *sight, sampler, stats);
  return silhouette_jump(ctx, in, *sight, *rays, sampler, stats);
}

/// Forward mode's Jacobian of an edge point: J[k] = g . v_t for every parameter k, v_t the velocity
/// of the edge point (1 - t) v0 + t v1 (its ends' velocities, edgetree::edge_end_velocity, from
/// `vel`) minus dp (3 x N, p's velocity).
template <int N>
Eigen::Matrix<double, 1, N> edge_point_jacobian(const SceneVelocities& vel, const edgetree::Edge& e, double t,
                                                const Vec3& g, const Eigen::Matrix<double, 3, N>& dp) {
  if (e.crossing) {
    const SceneVelocities::Block v0 = edgetree::edge_end_velocity(e, 0, vel),
                                 v1 = edgetree::edge_end_velocity(e, 1, vel);
    return g.transpose() * ((1 - t) * v0.template leftCols<N>() + t * v1.template leftCols<N>() - dp);
  }
  const auto& V = vel.position[e.shape];
  return g.transpose() * ((1 - t) * V[e.v0].template leftCols<N>() + t * V[e.v1].template leftCols<N>() - dp);
}

/// edge_jump_with for forward mode: J = edge_point_jacobian (1 x N, per parameter, written to `J`
/// whenever the edge point has a direction from p); a zero J is a zero contribution (no rays
/// traced). `dp`: p's velocity (3 x N). Returns the jump, or nothing for a zero contribution.
template <int N>
std::optional<Color> edge_jump(const PathContext& ctx, const SceneVelocities& vel, const EdgeJumpInputs& in,
                               const Eigen::Matrix<double, 3, N>& dp, Sampler& sampler, PathStats& stats,
                               Eigen::Matrix<double, 1, N>& J) {
  return edge_jump_with(ctx, in, sampler, stats, [&](const Vec3& g) {
    J = edge_point_jacobian<N>(vel, in.edge, in.t, g, dp);
    return !J.isZero(0.0);
  });
}

}  // namespace qsil
