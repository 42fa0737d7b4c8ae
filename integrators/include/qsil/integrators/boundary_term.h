#pragma once
/// @file boundary_term.h
/// The boundary term at a path vertex [QSS Eq. 3, Appendix A; docs/architecture.md §4-§5 "Evaluation"]:
///   sum over discontinuity edges of  integral_0^1 dL_i(w(t)) f_s(w(t), wo) J(t) dt,
///   J(t) = det(w0, w1, v_t) / |w_t|^3,  v_t = d(edge point)/dtheta - dp/dtheta,
/// estimated with the edge points of one traversal per vertex (EdgeSampler::sample_set: the
/// traversal's point, and for the edge forest the split bright loose edges' and, at a glossy
/// vertex or under a small quad light, one on its contour set's edges,
/// qsil/edgetree/contour_set.h). The velocity is relative to the shading point p, which moves
/// when it lies on a moving shape or an earlier vertex of its path moved (p carries that
/// derivative as a dual): then the edges of static
/// shapes (occluders, a mirror's outline, a light's outline) contribute too, so every shape's
/// edges are eligible; at a static p only moving shapes' edges are.
///
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

#include "qsil/edgetree/contour_set.h"
#include "qsil/edgetree/edge_forest.h"
#include "qsil/edgetree/edge_sampler.h"
#include "qsil/edgetree/mesh_edges.h"
#include "qsil/integrators/crossing_jump.h"
#include "qsil/integrators/edge_point.h"
#include "qsil/integrators/geometry_view.h"
#include "qsil/integrators/path_tracer.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <optional>
#include <vector>

namespace qsil {

/// What the boundary term needs besides the path context.
struct BoundaryContext {
  const edgetree::EdgeSampler* sampler = nullptr;  ///< the --boundary method's secondary edge sampler
  /// The mesh adjacency for contour sets at glossy vertices and under small quad lights
  /// (contour_probe; the quadric method in a scene with a glossy BSDF or a quad light), or null
  /// for none.
  const edgetree::ContourIndex* contours = nullptr;
  const SceneVelocities* velocities = nullptr;
  std::vector<bool> moving;  ///< shapes with non-zero velocity (eligible at a static p)
  std::vector<bool> all;     ///< every shape (eligible at a moving p)
  /// Secondary boundary-term traversals per path vertex, on average over a pixel's samples
  /// (EstimatorConfig::sppi; positive and finite): boundary_traversals() of them at every
  /// vertex of a sample's path, each weighted 1 / sppi.
  double sppi = 1.0;
  /// Splitting at fast shading points (boundary_split): a vertex whose shading point moves at
  /// speed s makes ceil(s / split_speed) traversals, at most kMaxBoundarySplit, for each one
  /// boundary_traversals schedules. 0: no splitting. Set from default_split_speed(method).
  double split_speed = 0;
  std::vector<edgetree::LightPolygon> lights;  ///< quad area lights for I_light [QSS 3.6]
  double env_weight = 1.0;                     ///< environment intensity (luminance of its mean)
  std::vector<double> emission;                ///< per shape: luminance of its emission (0: none)
  /// Per parameter: 1 / the largest |dx/dtheta_k| over all vertices (0: unused parameter), so that
  /// the leaves' normal-velocity factor weighs parameters of different units alike.
  std::array<double, kMaxParameters> velocity_scale{};
};

/// The LTC of a shading point's BSDF toward wo (local frame), with the albedo weight in norm.
inline edgetree::LTC bsdf_ltc(const BSDFDesc& b, Vec3 wo_local) {
  if (b.twosided && wo_local.z() < 0) wo_local.z() = -wo_local.z();
  edgetree::LTC ltc;
  if (b.type == BSDFDesc::Type::Diffuse) {
    ltc = edgetree::ltc_diffuse();
    ltc.norm = b.reflectance.mean();
  } else {
    ltc = edgetree::ltc_ggx(b.alpha, wo_local);
    ltc.norm *= b.specular_reflectance.mean();
  }
  if (!(wo_local.z() > 0)) ltc.norm = 0;  // a one-sided BSDF seen from behind reflects nothing
  return ltc;
}

/// The vertex of face `face` (one of edge `e`'s two faces) that is not on the edge (world).
inline const Vec3& opposite_vertex(const TriangleMesh& mesh, const edgetree::ForestEdge& e, int face) {
  return mesh.positions[size_t(edgetree::opposite_vertex_index(mesh, e, face))];
}

/// The face of edge `e` that lies in the plane of p's triangle `triangle` (unit geometric normal
/// `ng`, p on it; world coordinates): `triangle` itself when the edge bounds it, else a face of the
/// edge whose three vertices lie in that plane up to rounding (|ng . (x - p)| <= 2^-32 of the
/// coordinates' magnitude: far above double rounding, far below any modelled feature), else -1.
/// Such an edge lies in p's plane as an edge of p's own triangle does (a flat region split into
/// several triangles: a box's wall, a floor quad), and is treated as OwnFace says.
inline int face_in_plane(const TriangleMesh& mesh, const edgetree::ForestEdge& e, int triangle, const Vec3& ng,
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

/// The rays of the boundary term ignore the sampled edge's own two faces (an Embree filter on
/// their primitive ids: no absolute epsilon). `through_back_faces` as for every ray of the path
/// tracer (leaves_below).
inline IgnoreSet edge_faces(const edgetree::ForestEdge& e, bool through_back_faces) {
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
  const edgetree::ForestEdge& e = in.edge;
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
inline double plane_side(const Vec3& n01, const TriangleMesh& mesh, const edgetree::ForestEdge& e, int face,
                         const Vec3& p) {
  return n01.dot(opposite_vertex(mesh, e, face) - p);
}

/// Radiance leaving face `face` of edge point `in`'s edge (not a crossing) exactly at the edge
/// point toward p, along the unit direction w from p, continued with the remaining depth and the
/// random numbers of `rng`. The point is known: barycentrics (1-t at v0, t at v1) in the face's
/// vertex order (the face may be seen edge-on from p, where a ray-plane intersection degenerates).
inline Color edge_face_radiance(const PathContext& ctx, const EdgeJumpInputs& in, const Vec3& w, int face, Sampler& rng,
                                PathStats& stats) {
  const edgetree::ForestEdge& e = in.edge;
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
  return Color(trace_path(ctx, pv, {in.p, w, h, in.segments}, rng, stats));
}

/// The jump across a crease (edgetree::CreaseSet; both faces facing p) at edge point `in` seen
/// along `sight`: the two faces lie on opposite sides of the plane (p, edge); the radiance jumps
/// from one face's to the other's. Reynolds transport: jump = L(side -) - L(side +), + the side
/// (w0 x w1) points to. Nothing (a zero contribution) when the first face lies in that plane.
inline std::optional<Color> crease_jump(const PathContext& ctx, const EdgeJumpInputs& in, const EdgeSight& sight,
                                        Sampler& sampler, PathStats& stats) {
  const edgetree::ForestEdge& e = in.edge;
  const double s0 = plane_side(sight.n01, ctx.scene->shapes[e.shape].mesh, e, e.f0, in.p);
  if (s0 == 0) return std::nullopt;
  // Common random numbers: both faces continue their paths with the same random numbers, so
  // the difference is the jump itself (where the two paths differ), not two independent noises.
  Sampler same = sampler;
  const Color L0 = edge_face_radiance(ctx, in, sight.w, e.f0, sampler, stats),
              L1 = edge_face_radiance(ctx, in, sight.w, e.f1, same, stats);
  return s0 > 0 ? Color(L1 - L0) : Color(L0 - L1);
}

/// The jump across a silhouette or boundary edge (or an edge in p's plane, rays.own_occluder set)
/// at edge point `in` seen along `sight`: s (L_bg - L_fg), both faces on the occluder's side s.
/// Nothing (a zero contribution) when the occluding face lies in the plane (p, edge).
inline std::optional<Color> silhouette_jump(const PathContext& ctx, const EdgeJumpInputs& in, const EdgeSight& sight,
                                            const EdgeRays& rays, Sampler& sampler, PathStats& stats) {
  const edgetree::ForestEdge& e = in.edge;
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
  const edgetree::ForestEdge& e = in.edge;
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
Eigen::Matrix<double, 1, N> edge_point_jacobian(const SceneVelocities& vel, const edgetree::ForestEdge& e, double t,
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

/// The core of a light contour set (qsil/edgetree/contour_set.h "Light contour sets") for query
/// q, written into `probe` (axis, cos_half_angle, to_cosine, cos_core): of the quad lights of q
/// that emit toward p (edgetree::light_toward) and reach above p's shading horizon, the one with
/// the largest radiance × area × |cos at the light| / distance² (from its centre), bounded by the
/// circular cone about the direction to its centre through its farthest corner (a cap under π/2
/// holds the spherical quad of its corners); to_cosine a rotation taking the axis to +z, so the
/// core is that cone. Returns false (probe untouched) where no light qualifies or the cone's half-angle is above
/// kContourMaxHalfAngle. `shape` receives the light's shape (its probe rays pass through it).
inline bool light_core(const edgetree::SilhouetteQuery& q, edgetree::ContourProbe& probe, int& shape) {
  if (!q.lights) return false;
  const edgetree::LightPolygon* best = nullptr;
  double best_weight = 0;
  Vec3 best_centre = Vec3::Zero();
  for (const edgetree::LightPolygon& l : *q.lights) {
    std::array<Vec3, 4> local;  // the corners relative to p in the shading frame
    if (!edgetree::light_toward(l, q, local)) continue;
    bool above = false;
    for (const Vec3& c : local) above |= c.z() > 0;
    if (!above) continue;
    const Vec3 centre = 0.25 * (l.corners[0] + l.corners[1] + l.corners[2] + l.corners[3]);
    const Vec3 d = centre - q.p;
    const double d2 = d.squaredNorm();
    const double cos_light = -l.normal.dot(d) / std::sqrt(d2);
    const double area = 0.5 * ((l.corners[2] - l.corners[0]).cross(l.corners[3] - l.corners[1])).norm();
    const double w = l.weight * area * cos_light / d2;
    if (w > best_weight) {
      best_weight = w;
      best = &l;
      best_centre = centre;
    }
  }
  if (!best) return false;
  const Vec3 axis = (best_centre - q.p).normalized();
  double cos_half = 1;
  for (const Vec3& c : best->corners) cos_half = std::min(cos_half, axis.dot((c - q.p).normalized()));
  if (!(cos_half >= std::cos(edgetree::kContourMaxHalfAngle))) return false;
  const Vec3 s = axis.unitOrthogonal(), t = axis.cross(s);
  probe.axis = axis;
  probe.cos_half_angle = cos_half;
  probe.to_cosine << s.transpose(), t.transpose(), axis.transpose();
  probe.cos_core = cos_half;
  shape = best->shape;
  return true;
}

/// The contour probe of a boundary query (qsil/edgetree/contour_set.h). Its core: where q's LTC is
/// glossy and the cone that bounds its core (ltc_core_cone with kContourConeMass) has a half-angle
/// of at most kContourMaxHalfAngle, the lobe's core in world coordinates; elsewhere (a cosine or
/// wide lobe) the cone of a small quad light (light_core). The probe is made where that cone meets
/// an eligible shape's bounding sphere (ContourIndex::cone_meets_shapes): the first hit of the ray
/// from the shading point along the cone's axis, kept when it is on an eligible shape other than
/// the probed light (a ray that reaches the light met nothing in front of it); where it is not (a
/// miss, the light, or a static shape in front), the first hits of kContourRingRays rays around
/// the axis, at kContourRingAngle times the core's extent (a ring in the core's cosine domain
/// mapped back, so it stays inside a stretched core), those kept by the same rule. Each ray passes
/// through back faces where its direction leaves below the surface, as every ray of the path
/// tracer does. `rays` receives the number of rays traced. A probe with no hit (count 0) gives no
/// contour set.
template <class T>
edgetree::ContourProbe contour_probe(const PathContext& ctx, const edgetree::ContourIndex& contours,
                                     const SurfaceInteraction<T>& si, const Vec3& wo_world,
                                     const edgetree::SilhouetteQuery& q, int& rays) {
  rays = 0;
  edgetree::ContourProbe probe;
  Mat3 M = Mat3::Identity();  // the lobe's LTC matrix (M_inv^-1): its cosine domain back to local directions
  int light = -1;             // the probed light's shape: its hits are misses
  bool lobe = false;
  if (!edgetree::is_cosine_lobe(q.ltc) && q.ltc.norm > 0) {
    const edgetree::LTCCone cone = edgetree::ltc_core_cone(q.ltc, edgetree::kContourConeMass);
    if (cone.cos_half_angle >= std::cos(edgetree::kContourMaxHalfAngle)) {
      lobe = true;
      probe.axis = q.frame.to_world(cone.axis).normalized();
      probe.cos_half_angle = cone.cos_half_angle;
      Mat3 to_local;
      to_local << q.frame.s.transpose(), q.frame.t.transpose(), q.frame.n.transpose();
      probe.to_cosine = q.ltc.M_inv * to_local;
      probe.cos_core = std::sqrt(1.0 - edgetree::kContourConeMass);
      M = q.ltc.M_inv.inverse();
    }
  }
  if (!lobe && !light_core(q, probe, light)) return probe;
  if (!contours.cone_meets_shapes(q.p, probe.axis, probe.cos_half_angle, q.eligible)) return probe;
  auto trace = [&](const Vec3& dir) {
    IgnoreSet ignore;
    ignore.through_back_faces = leaves_below(si, wo_world, dir);
    const Vec3 origin = spawn_origin(si, dir);
    ++rays;
    const Hit h = ctx.tracer->intersect(origin, dir, kInf, ignore);
    if (!h.valid() || h.shape == light || !q.is_eligible(h.shape)) return;
    probe.hits[size_t(probe.count++)] = {h.shape, h.triangle, Vec3(origin + h.t * dir), dir};
  };
  trace(probe.axis);
  if (probe.count == 0) {
    // The ring: directions (k tan(gamma) cos(phi), k tan(gamma) sin(phi), 1) of the cosine domain,
    // gamma the core's half-angle there (a lobe's: sin^2 gamma = kContourConeMass; a light's: cos
    // gamma = cos_core).
    const double tan_core = lobe ? std::sqrt(edgetree::kContourConeMass / (1.0 - edgetree::kContourConeMass))
                                 : std::sqrt(std::max(0.0, 1.0 - probe.cos_core * probe.cos_core)) / probe.cos_core;
    const double r = edgetree::kContourRingAngle * tan_core;
    for (int k = 0; k < edgetree::kContourRingRays; ++k) {
      const Vec3 c(r * edgetree::kContourRingCos[k], r * edgetree::kContourRingSin[k], 1.0);
      // A lobe's ring through its LTC to the local frame; a light's through the core's rotation.
      const Vec3 d = lobe ? Vec3(M * c) : Vec3(probe.to_cosine.transpose() * c);
      if (d.allFinite() && d.squaredNorm() > 0) trace(lobe ? q.frame.to_world(d.normalized()) : Vec3(d.normalized()));
    }
  }
  return probe;
}

/// How many secondary boundary traversals sample `sample` of pixel `pixel` makes at each vertex of
/// its path, at `rate` = BoundaryContext::sppi: the whole part of the rate, plus one
/// where a stratified pick over the pixel's samples selects it: with f the fraction of the rate
/// and phi uniform in [0, 1) drawn once per pixel (Sampler(seed, pixel, 0, 3): the same for every
/// sample range and process split), sample s is picked iff floor(f (s + 1) + phi) > floor(f s +
/// phi). Every sample is picked with probability f (phi is uniform, to its 32 bits), so weighting each
/// traversal by 1 / rate is unbiased; and any n consecutive samples hold floor(f n) or ceil(f n)
/// picks, so unlike Russian roulette per sample the term's own mean adds no variance (a rate of
/// 1/2 is one boundary estimate every other sample, the sppi of Mitsuba 3's projective
/// integrators). The pixel's samples are then not identically distributed, so the estimator marks
/// the picked ones as a stratum of their own (Film::add_sample), whose variance the film's
/// standard error takes apart.
inline int boundary_traversals(double rate, uint64_t seed, uint64_t pixel, uint64_t sample) {
  const int whole = int(rate);
  const double f = rate - double(whole);
  if (!(f > 0)) return whole;
  const double phi = Sampler(seed, pixel, 0, 3).next();
  const double s = double(sample);
  return whole + int(std::floor(f * (s + 1.0) + phi) - std::floor(f * s + phi));
}

/// The most traversals boundary_split makes of one.
inline constexpr int kMaxBoundarySplit = 16;

/// How many traversals stand for each one boundary_traversals schedules at the vertex of query `q`
/// (splitting, as in adjoint-driven Russian roulette and splitting, Vorba & Křivánek 2016, with the
/// shading point's speed as the driver): with s = max_k |dp/dtheta_k| velocity_scale[k], the speed
/// of p in units of the fastest mesh vertex of each parameter (q.dp, q.velocity_scale; 0 without
/// q.velocities, e.g. reverse mode), ceil(s / bctx.split_speed) clamped to [1,
/// kMaxBoundarySplit]; 1 when bctx.split_speed is 0.
/// Why: with directions fixed, a point a ray meets on a moving surface at an angle of incidence
/// with cosine c slides along the ray at about 1/c the surface's speed, so J = n . (v - dp) of
/// every edge seen from p grows with s, and so does the variance of one traversal's estimate
/// (the choice of edge; the variance across pixel samples of the exact value is another matter).
/// Splitting a traversal into m, each weighted 1/m, keeps the estimate unbiased for any m that
/// depends only on the vertex (p, dp), and divides that variance by m at m times the cost; m
/// proportional to s is the allocation that minimises variance x cost when the variance grows
/// as s^2 (the rate's own argument, docs/design-notes.md "How many boundary samples per pixel
/// sample", per vertex). Such points are rare (grazing hits), so the cost stays small: measured
/// in docs/architecture.md §5 "Splitting at fast shading points".
inline int boundary_split(const BoundaryContext& bctx, const edgetree::SilhouetteQuery& q) {
  if (!(bctx.split_speed > 0) || !q.velocities) return 1;
  double speed = 0;
  for (int k = 0; k < q.velocities->num_params; ++k)
    speed = std::max(speed, q.dp.col(k).norm() * q.velocity_scale[size_t(k)]);
  // The clamp before the conversion keeps a non-finite speed from becoming an undefined int.
  return int(std::clamp(std::ceil(speed / bctx.split_speed), 1.0, double(kMaxBoundarySplit)));
}

/// A path vertex at which the secondary boundary term is sampled (for_each_boundary_sample). T is
/// the path's real type (double or a dual; only values are read). References are to the caller's
/// objects and must outlive the call.
template <class T>
struct BoundaryVertex {
  const SurfaceInteraction<T>& si;  ///< the vertex's surface interaction (world)
  const ShadingPoint<T>& sp;        ///< its shading point: BSDF and shading frame
  /// The boundary query, set up by the caller (boundary_query; eligibility, velocities); copied,
  /// and the copy's contour set made, by for_each_boundary_sample.
  const edgetree::SilhouetteQuery& query;
  Vec3 wo_local = Vec3::Zero();      ///< unit direction toward the vertex's viewer, in sp's shading frame
  Color throughput = Color::Zero();  ///< T: the detached throughput from the camera to the vertex
  int segments = 0;                  ///< segments of the path before the vertex (trace_path's `segments`)
  int traversals = 0;                ///< boundary traversals at the vertex (boundary_traversals; <= 0: none)
};

/// The secondary boundary term's samples at one path vertex (shared by forward mode, BoundaryHook,
/// and reverse mode, integrators/reverse.cpp) `vertex` (BoundaryVertex): vertex.traversals
/// traversals of bctx.sampler (boundary_traversals) for query q = vertex.query (set up by the
/// caller: eligibility, velocities; its contour set is made here when bctx.contours is set:
/// contour_probe, ContourIndex::contour_edges), each split into m = boundary_split(bctx, q), drawing from
/// `sampler`; for each edge point with f_s != 0, `accept(edge, t, g)` decides before any ray
/// whether it can contribute (edge_jump_with), and each contributing one is handed to
/// `visit(edge, t, weight, g)` with weight = T f_s jump / (pdf r m), r = bctx.sppi
/// and T the detached throughput (the vertex's derivative gains weight (g . v_t)). Counts
/// traversals (the split ones each), zero traversals and thread time.
template <class T, class Accept, class Visit>
void for_each_boundary_sample(const PathContext& ctx, const BoundaryContext& bctx, const BoundaryVertex<T>& vertex,
                              Sampler& sampler, PathStats& stats, Accept&& accept, Visit&& visit) {
  const SurfaceInteraction<T>& si = vertex.si;
  const ShadingPoint<T>& sp = vertex.sp;
  const Vec3& wo_local = vertex.wo_local;
  const Color& throughput = vertex.throughput;
  int traversals = vertex.traversals;
  if (traversals <= 0) return;
  edgetree::SilhouetteQuery q = vertex.query;
  const int split = boundary_split(bctx, q);
  traversals *= split;
  const double rate = bctx.sppi * double(split);
  const auto t0 = std::chrono::steady_clock::now();
  const Vec3 wo_world = q.frame.to_world(wo_local);
  // ---- The contour set of a glossy vertex: made once, used by every traversal here. The
  // traversals leave no other boundary query open on this thread meanwhile (their radiance paths
  // have no vertex hook), so per-thread storage serves.
  thread_local std::vector<const edgetree::ForestEdge*> contour;
  contour.clear();
  if (bctx.contours) {
    int rays = 0;
    const edgetree::ContourProbe probe = contour_probe(ctx, *bctx.contours, si, wo_world, q, rays);
    stats.rays += uint64_t(rays);
    if (probe.count > 0) bctx.contours->contour_edges(probe, q.p, q.eligible, contour);
  }
  q.contour = contour;
  edgetree::SilhouetteSampleSet set;
  for (int sample = 0; sample < traversals; ++sample) {
    ++stats.boundary_traversals;
    bctx.sampler->sample_set(
        q, [&sampler] { return sampler.next(); }, set);
    // Counted per traversal: zero when none of its edge points contributed.
    bool contributed = false;
    for (int k = 0; k < set.count; ++k) {
      const edgetree::SilhouetteSample& s = set.samples[size_t(k)];
      if (!(s.pdf > 0)) continue;
      const edgetree::ForestEdge& e = *s.edge;
      const Vec3 w = (e.p0 + s.t * (e.p1 - e.p0) - q.p).normalized();
      const Color f = bsdf_eval<double>(*sp.bsdf, q.frame.to_local(w), wo_local);
      if ((f == 0).all()) continue;
      Vec3 g;
      OwnFace own;
      if (e.crossing) {
        own.up = value(si.ng).dot(wo_world) < 0 ? Vec3(-value(si.ng)) : value(si.ng);  // crossing_jump
      } else if (e.shape == si.shape) {
        own.face = face_in_plane(ctx.scene->shapes[size_t(e.shape)].mesh, e, si.triangle, value(si.ng), q.p);
        if (own.face >= 0) own.up = value(si.ng).dot(wo_world) < 0 ? Vec3(-value(si.ng)) : value(si.ng);
      }
      // An edge in p's plane takes its rays below that plane (edge_jump_with): its origin there.
      const Vec3 vis_origin = spawn_origin(si, own.face >= 0 ? Vec3(-own.up) : w);
      const EdgeJumpInputs in{.edge = e,
                              .t = s.t,
                              .p = q.p,
                              .vis_origin = vis_origin,
                              .through_back_faces = leaves_below(si, wo_world, w),
                              .own = own,
                              .segments = vertex.segments};
      const std::optional<Color> jump = edge_jump_with(ctx, in, sampler, stats, [&](const Vec3& gv) {
        g = gv;
        return accept(e, s.t, gv);
      });
      if (!jump || (*jump == 0).all()) continue;
      contributed = true;
      visit(e, s.t, Color(throughput * f * *jump / (s.pdf * rate)), g);
    }
    stats.boundary_zero += !contributed;
  }
  stats.boundary_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// The shading point's part of a boundary query: position, frame, the BSDF's LTC toward wo and the
/// importance inputs of bctx (eligibility, velocities: the caller's).
template <class T>
edgetree::SilhouetteQuery boundary_query(const BoundaryContext& bctx, const SurfaceInteraction<T>& si,
                                         const ShadingPoint<T>& sp, const Vec3& wo_local) {
  edgetree::SilhouetteQuery q;
  q.p = value(si.p);
  q.frame = sp.frame_value;
  q.ltc = bsdf_ltc(*sp.bsdf, wo_local);
  q.lights = &bctx.lights;
  q.env_weight = bctx.env_weight;
  q.emission = &bctx.emission;
  return q;
}

/// The vertex hook of trace_path that adds the secondary boundary term (DualView<N> paths only).
template <int N>
struct BoundaryHook {
  const PathContext* ctx;
  const BoundaryContext* bctx;
  Sampler* sampler;  ///< a stream of its own, so the hook leaves the path's own decisions unchanged
  int traversals;    ///< at every vertex (boundary_traversals of the sample)

  void operator()(const SurfaceInteraction<Dual<N>>& si, const ShadingPoint<Dual<N>>& sp, const Vec3& wo_local,
                  const ColorT<Dual<N>>& beta, int seg, Sampler&, PathStats& stats, ColorT<Dual<N>>& L) const {
    // ---- dp/dtheta: does the shading point move?
    Eigen::Matrix<double, 3, N> dp;
    for (int i = 0; i < 3; ++i) dp.row(i) = si.p[i].derivatives().transpose();
    edgetree::SilhouetteQuery q = boundary_query(*bctx, si, sp, wo_local);
    q.eligible = !dp.isZero(0.0) ? &bctx->all : &bctx->moving;
    q.velocities = bctx->velocities;
    q.dp.setZero();
    q.dp.template leftCols<N>() = dp;
    q.velocity_scale = bctx->velocity_scale;
    Eigen::Matrix<double, 1, N> J;  // of the sample being evaluated
    const BoundaryVertex<Dual<N>> vertex{.si = si,
                                         .sp = sp,
                                         .query = q,
                                         .wo_local = wo_local,
                                         .throughput = value(beta),
                                         .segments = seg,
                                         .traversals = traversals};
    for_each_boundary_sample(
        *ctx, *bctx, vertex, *sampler, stats,
        [&](const edgetree::ForestEdge& e, double t, const Vec3& g) {
          J = edge_point_jacobian<N>(*bctx->velocities, e, t, g, dp);
          return !J.isZero(0.0);
        },
        [&](const edgetree::ForestEdge&, double, const Color& weight, const Vec3&) {
          for (int c = 0; c < 3; ++c) L[c] += Dual<N>(0.0, (weight[c] * J).transpose());
        });
  }
};

}  // namespace qsil
