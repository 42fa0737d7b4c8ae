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
/// The evaluation of one edge point: edge_jump.h; how many traversals: boundary_schedule.h; the
/// contour probe: contour_probe.h; forward mode's hook: boundary_hook.h.

#include "qsil/edgetree/bsdf_ltc.h"
#include "qsil/edgetree/contour_set.h"
#include "qsil/edgetree/edge_sampler.h"
#include "qsil/integrators/boundary_context.h"
#include "qsil/integrators/boundary_schedule.h"
#include "qsil/integrators/contour_probe.h"
#include "qsil/integrators/edge_jump.h"
#include "qsil/integrators/path_tracer.h"

#include <chrono>
#include <optional>
#include <type_traits>
#include <vector>

namespace qsil {

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
  /// Training a forest guide (edgetree::ForestGuide): each contributing edge point that a
  /// traversal chose appends here one record per guided choice it made (its slot, value
  /// guide_record_value / the choice's unguided probability); null: none.
  std::vector<edgetree::GuideRecord>* guide_records = nullptr;
};

/// The training value of an edge point of the boundary term (edgetree::GuideRecord::value): the
/// magnitude of its contribution, mean |weight| over the colour channels (weight as
/// for_each_boundary_sample hands to `visit`) times sum_k |g . v_t,k| velocity_scale[k], v_t the
/// edge point's velocity relative to p (q.velocities, q.dp; without velocities, reverse mode:
/// |g|): the boundary term's magnitude per parameter, parameters of different units weighed alike
/// as in the edge choice (edgetree::velocity_factor).
inline double guide_record_value(const edgetree::SilhouetteQuery& q, const edgetree::Edge& e, double t,
                                 const Color& weight, const Vec3& g) {
  const double w = weight.abs().mean();
  if (!q.velocities) return w * g.norm();
  const SceneVelocities::Block v = (1 - t) * edgetree::edge_end_velocity(e, 0, *q.velocities) +
                                   t * edgetree::edge_end_velocity(e, 1, *q.velocities) - q.dp;
  double m = 0;
  for (int k = 0; k < q.velocities->num_params; ++k) m += std::abs(g.dot(v.col(k))) * q.velocity_scale[size_t(k)];
  return w * m;
}

/// The contour set of a vertex's query, in its edge-choice scratch (for_each_boundary_sample).
struct ContourEdgesBuffer {
  std::vector<const edgetree::Edge*> edges;
};

/// The factors of one edge point's weight (for_each_boundary_sample), for a visit that asks for
/// them: the largest samples' decomposition (integrators/vertex_recorder.h).
struct EdgePointFactors {
  double pdf = 0;               ///< the point's pdf: discrete edge probability times density of t (per unit t)
  Color jump = Color::Zero();   ///< the radiance's jump across the edge at the point (edge_jump_with)
  Color bsdf = Color::Zero();   ///< f_s toward the point (cosine included as bsdf_eval gives it)
  double rate = 0;              ///< r m: edge points per unit of the estimate (boundary_ctx.sppi times the split)
};

/// The secondary boundary term's samples at one path vertex (shared by forward mode, BoundaryHook,
/// and reverse mode, integrators/reverse.cpp) `vertex` (BoundaryVertex): vertex.traversals
/// traversals of boundary_ctx.sampler (boundary_traversals) for query q = vertex.query (set up by the
/// caller: eligibility, velocities; its contour set is made here when boundary_ctx.contours is set:
/// contour_probe, ContourIndex::contour_edges), each split into m = boundary_split(boundary_ctx, q), drawing from
/// `sampler`; for each edge point with f_s != 0, `accept(edge, t, g)` decides before any ray
/// whether it can contribute (edge_jump_with), and each contributing one is handed to
/// `visit(edge, t, weight, g)` with weight = T f_s jump / (pdf r m), r = boundary_ctx.sppi
/// and T the detached throughput (the vertex's derivative gains weight (g . v_t)); a visit that
/// takes a fifth argument gets the weight's factors too (EdgePointFactors). Counts
/// traversals (the split ones each), zero traversals and thread time.
template <class T, class Accept, class Visit>
void for_each_boundary_sample(const PathContext& ctx, const BoundaryContext& boundary_ctx, const BoundaryVertex<T>& vertex,
                              Sampler& sampler, PathStats& stats, Accept&& accept, Visit&& visit) {
  const SurfaceInteraction<T>& si = vertex.si;
  const ShadingPoint<T>& sp = vertex.sp;
  const Vec3& wo_local = vertex.wo_local;
  const Color& throughput = vertex.throughput;
  int traversals = vertex.traversals;
  if (traversals <= 0) return;
  edgetree::SilhouetteQuery q = vertex.query;
  const int split = boundary_split(boundary_ctx, q);
  traversals *= split;
  const double rate = boundary_ctx.sppi * double(split);
  const auto t0 = std::chrono::steady_clock::now();
  const Vec3 wo_world = q.frame.to_world(wo_local);
  // ---- The contour set of a glossy vertex: made once, used by every traversal here, in the
  // query's scratch (the traversals leave no other boundary query open on this thread meanwhile:
  // their radiance paths have no vertex hook).
  edgetree::EdgeChoiceScratch fallback;
  std::vector<const edgetree::Edge*>& contour =
      edgetree::scratch_buffer<ContourEdgesBuffer>(q.scratch, fallback).edges;
  contour.clear();
  if (boundary_ctx.contours) {
    int rays = 0;
    const edgetree::ContourProbe probe = contour_probe(ctx, *boundary_ctx.contours, si, wo_world, q, rays);
    stats.rays += uint64_t(rays);
    if (probe.count > 0) boundary_ctx.contours->contour_edges(probe, q.p, q.eligible, contour, q.scratch);
  }
  q.contour = contour;
  edgetree::SilhouetteSampleSet set;
  for (int sample = 0; sample < traversals; ++sample) {
    ++stats.boundary_traversals;
    boundary_ctx.sampler->sample_set(
        q, [&sampler] { return sampler.next(); }, set);
    // Counted per traversal: zero when none of its edge points contributed.
    bool contributed = false;
    for (int k = 0; k < set.count; ++k) {
      const edgetree::SilhouetteSample& s = set.samples[size_t(k)];
      if (!(s.pdf > 0)) continue;
      const edgetree::Edge& e = *s.edge;
      const Vec3 w = (e.p0 + s.t * (e.p1 - e.p0) - q.p).normalized();
      const Color f = bsdf_eval<double>(*sp.bsdf, q.frame.to_local(w), wo_local);
      if ((f == 0).all()) continue;
      Vec3 g;
      const EdgeJumpInputs in = vertex_edge_inputs(ctx, e, s.t, si, wo_world, w, vertex.segments);
      const std::optional<Color> jump = edge_jump_with(ctx, in, sampler, stats, [&](const Vec3& gv) {
        g = gv;
        return accept(e, s.t, gv);
      });
      if (!jump || (*jump == 0).all()) continue;
      contributed = true;
      const Color weight = throughput * f * *jump / (s.pdf * rate);
      if (vertex.guide_records && s.guide_levels > 0) {
        const double v = guide_record_value(q, e, s.t, weight, g);
        for (int l = 0; l < s.guide_levels; ++l)
          vertex.guide_records->push_back({q.p, s.guide_slots[size_t(l)], v / s.guide_pu[size_t(l)]});
      }
      if constexpr (std::is_invocable_v<Visit&, const edgetree::Edge&, double, const Color&, const Vec3&,
                                        const EdgePointFactors&>)
        visit(e, s.t, weight, g, EdgePointFactors{s.pdf, *jump, f, rate});
      else
        visit(e, s.t, weight, g);
    }
    stats.boundary_zero += !contributed;
  }
  stats.boundary_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// The shading point's part of a boundary query: position, frame, the BSDF's LTC toward wo and the
/// importance inputs of boundary_ctx (eligibility, velocities: the caller's), and this thread's
/// edge-choice scratch (`scratch`, null: none).
template <class T>
edgetree::SilhouetteQuery boundary_query(const BoundaryContext& boundary_ctx, const SurfaceInteraction<T>& si,
                                         const ShadingPoint<T>& sp, const Vec3& wo_local,
                                         edgetree::EdgeChoiceScratch* scratch) {
  edgetree::SilhouetteQuery q;
  q.scratch = scratch;
  q.p = value(si.p);
  q.frame = sp.frame_value;
  q.ltc = edgetree::bsdf_ltc(*sp.bsdf, wo_local);
  q.lights = &boundary_ctx.lights;
  q.light_spheres = &boundary_ctx.light_spheres;
  q.env_weight = boundary_ctx.env_weight + edgetree::enclosing_light_weight(q.light_spheres, q.p);
  q.emission = &boundary_ctx.emission;
  q.guide = boundary_ctx.guide;
  return q;
}

/// What the vertex hooks of both modes hold (forward mode's BoundaryHook, boundary_hook.h; reverse
/// mode's in integrators/reverse.cpp), which differ only in what they do with each sample.
struct BoundaryHookBase {
  const PathContext* ctx;
  const BoundaryContext* boundary_ctx;
  Sampler* sampler;  ///< a stream of its own, so the hook leaves the path's own decisions unchanged
  int traversals;    ///< at every vertex (boundary_traversals of the sample)
  edgetree::EdgeChoiceScratch* scratch;  ///< this thread's edge-choice scratch
  /// Training a forest guide: the records of this hook's vertices (BoundaryVertex::guide_records);
  /// null: none.
  std::vector<edgetree::GuideRecord>* guide_records = nullptr;

  /// The path vertex (si, sp, viewer direction wo_local, throughput beta after `seg` segments)
  /// for query q, with this hook's traversals.
  template <class T>
  BoundaryVertex<T> vertex(const SurfaceInteraction<T>& si, const ShadingPoint<T>& sp,
                           const edgetree::SilhouetteQuery& q, const Vec3& wo_local, const ColorT<T>& beta,
                           int seg) const {
    return {.si = si,
            .sp = sp,
            .query = q,
            .wo_local = wo_local,
            .throughput = value(beta),
            .segments = seg,
            .traversals = traversals,
            .guide_records = guide_records};
  }
};

}  // namespace qsil
