#pragma once
/// @file regularized_tracer.h
/// The path tracer of the `regularized` method (docs/architecture.md §14): path_tracer.h's
/// unidirectional tracer (NEE + BSDF sampling, power-heuristic MIS, directions fixed, pdfs and MIS
/// weights detached) with every ray's first hit replaced by the regularised visibility of
/// qsil/integrators/regularized_visibility.h: each segment sees one term of its ray, sampled with
/// probability W and weighted by W(theta) / W, and NEE weighs a light point by the sum of the
/// weights of the emitter terms its ray sees (their blurred margins included). Over DualView<N> it returns the regularised image's
/// interior-term derivative, which is the regularised image's whole derivative (it is smooth).
///
/// MIS: NEE keeps a light point only when it lies on the first triangle its ray crosses inside
/// (points behind it, e.g. on the far side of a sphere light, are dropped), so the NEE density of
/// a direction is the light-sampling density of that triangle converted to solid angle when it is
/// an emitter facing the ray's origin, else 0; both strategies take it from the same candidates,
/// so they weigh the same integrand. A direction that sees an emitter only in the blurred margin
/// beyond its edges has NEE density 0: BSDF sampling alone estimates it.

#include "qsil/integrators/path_tracer.h"
#include "qsil/integrators/regularized_visibility.h"

namespace qsil {

/// What a regularised path needs beyond PathContext.
struct RegularizedContext {
  const PathContext* path = nullptr;
  const SoftScene* soft = nullptr;
};

/// The solid-angle density with which NEE (area lights) produces the direction of `ray` from its
/// origin, counting only points on the first triangle the ray crosses inside (detached; see the
/// file comment): candidates stop there, so the sum has at most one term.
inline double soft_nee_pdf(const PathContext& ctx, const SoftRay& ray) {
  if (!ctx.area_lights || ctx.area_lights->empty()) return 0.0;
  double pdf = 0;
  for (const SoftCandidate& c : ray.candidates)
    if (c.inside && c.cos < 0 && ctx.scene->shapes[size_t(c.shape)].is_emitter)
      pdf += (1.0 - ctx.p_environment) * ctx.area_lights->pdf_area() * c.t * c.t / -c.cos;
  return pdf;
}

/// The emitted radiance a ray sees: sum over its emitter candidates facing its origin of
/// W_k L_e,k, over T (weights from `w`).
template <class T>
ColorT<T> soft_emission(const PathContext& ctx, const SoftRay& ray, const SoftWeights<T>& w) {
  ColorT<T> E = lift<T>(Color::Zero().eval());
  for (size_t k = 0; k < ray.candidates.size(); ++k) {
    const SoftCandidate& c = ray.candidates[k];
    const Shape& shape = ctx.scene->shapes[size_t(c.shape)];
    if (shape.is_emitter && c.cos < 0) E += lift<T>(Color(shape.radiance)) * w.w[k];
  }
  return E;
}

/// Radiance arriving at `origin` from direction `dir` under regularised visibility, with its
/// derivative when the view's scalar type is a dual (see the file comment). `skip_shape`,
/// `skip_triangle` and `tmin`: the triangle the ray leaves and the relative distance of its own
/// surface (soft_ray_tmin), or -1, -1, 0 for a camera ray. `pdf_prev`: the detached solid-angle
/// pdf with which dir was BSDF-sampled (0: not, as for a camera ray).
template <class View>
ColorT<typename View::Real> trace_regularized_path(const RegularizedContext& rc, const View& view,
                                                   Vec3T<typename View::Real> o, Vec3 d, Sampler& sampler,
                                                   PathStats& stats, int skip_shape = -1, int skip_triangle = -1,
                                                   double tmin = 0, double pdf_prev = 0) {
  using T = typename View::Real;
  constexpr double uniform_share = std::is_same_v<T, double> ? 0.0 : kDerivativeDiffuseUniformShare;
  const PathContext& ctx = *rc.path;
  const Scene& scene = *ctx.scene;
  const Vec3 local_origin = ctx.tracer->local_origin();
  ColorT<T> L = lift<T>(Color::Zero().eval());
  ColorT<T> beta = lift<T>(Color::Ones().eval());
  SoftRay ray, shadow;
  SoftWeights<T> w, shadow_w;
  for (int seg = 1;; ++seg) {
    ++stats.rays;
    find_soft_candidates(scene, ctx.tracer, *rc.soft, value(o), d, tmin, kInf, skip_shape, skip_triangle, ray);
    const int k = pick_soft_candidate(ray, sampler.next());
    soft_weights(view, rc.soft->regularization(), ray, o, d, w);
    beta = beta * w.ratio(k);
    // ---- The background: the environment (MIS against environment NEE).
    if (k < 0) {
      if (ctx.environment && ctx.environment->present()) L += beta * lift<T>(escaped_radiance(ctx, d, pdf_prev));
      break;
    }
    const SoftCandidate& c = ray.candidates[size_t(k)];
    Hit hit;
    hit.shape = c.shape;
    hit.triangle = c.triangle;
    hit.t = c.t;
    const SurfaceInteraction<T> si = make_interaction(view, hit, o, d, local_origin);
    if (!value(si.p).allFinite() || !value(si.ns).allFinite()) break;
    const Shape& shape = scene.shapes[size_t(c.shape)];
    const Vec3 wo_world = -d;
    // ---- Emission of the sampled term (MIS against area-light NEE).
    if (shape.is_emitter && c.cos < 0) {
      const double mis = pdf_prev > 0 ? power_heuristic(pdf_prev, soft_nee_pdf(ctx, ray)) : 1.0;
      L += beta * lift<T>(Color(shape.radiance * mis));
    }
    if (seg >= ctx.max_depth) break;

    const VertexBSDF<T> vertex = vertex_bsdf(ctx, si, wo_world);
    const ShadingPoint<T>& sp = vertex.sp;
    const Vec3& wo_value = vertex.wo_value;
    const auto bsdf_toward = [&](const Vec3& wi) { return vertex.toward(wi); };
    const Vec3 p = value(si.p);
    const double next_tmin = soft_ray_tmin(si.scale, p, local_origin);

    // ---- Next-event estimation: the light drawn as sample_direct_light draws it.
    {
      const LightDirection ld = sample_light_direction(ctx, p, sampler);
      const Vec3& wi = ld.wi;
      double pdf_light = ld.environment ? ld.pdf : 0.0;
      if (ld.valid) {
        const ColorT<T> f = bsdf_toward(wi);
        if ((value(f) != 0).any()) {
          ++stats.rays;
          find_soft_candidates(scene, ctx.tracer, *rc.soft, p, wi, next_tmin, kInf, c.shape, c.triangle, shadow);
          // A light point is kept only on the first triangle its ray crosses inside (the last
          // candidate): a point behind it is a sample of that triangle's direction too, which
          // soft_nee_pdf does not count (nothing behind it is a candidate).
          if (!ld.environment)
            pdf_light = !shadow.candidates.empty() && shadow.candidates.back().inside &&
                                shadow.candidates.back().shape == ld.area.shape &&
                                shadow.candidates.back().triangle == ld.area.triangle
                            ? soft_nee_pdf(ctx, shadow)
                            : 0.0;
          if (pdf_light > 0) {
            soft_weights(view, rc.soft->regularization(), shadow, si.p, wi, shadow_w);
            const double mis =
                power_heuristic(pdf_light, bsdf_pdf(*sp.bsdf, sp.frame_value.to_local(wi), wo_value, uniform_share));
            const ColorT<T> seen = ld.environment ? ColorT<T>(lift<T>(ld.radiance) * shadow_w.background)
                                           : soft_emission(ctx, shadow, shadow_w);
            L += beta * f * seen * T(mis / pdf_light);
          }
        }
      }
    }

    // ---- BSDF sampling: a detached direction, then the throughput re-evaluated over T.
    const BSDFSample bs = bsdf_sample(*sp.bsdf, wo_value, sampler.next2(), uniform_share);
    if (!bs.valid || !(bs.pdf > 0)) break;
    const Vec3 wi = sp.frame_value.to_world(bs.wi).normalized();
    beta = beta * bsdf_toward(wi) / T(bs.pdf);
    if ((value(beta) == 0).all()) break;
    pdf_prev = bs.pdf;
    o = si.p;
    d = wi;
    skip_shape = c.shape;
    skip_triangle = c.triangle;
    tmin = next_tmin;
  }
  return L;
}

}  // namespace qsil
