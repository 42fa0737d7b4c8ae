#pragma once
/// @file path_tracer.h
/// Unidirectional path tracing with next-event estimation and MIS (power heuristic) between BSDF
/// sampling and emitter sampling, written once over a geometry view (PrimalView: radiance;
/// DualView<N>: radiance and its interior-term derivative in forward mode).
///
/// Parametrization (docs/architecture.md §4, [QSS Eq. 2]): every direction is sampled from detached values
/// and then held fixed; what depends on theta is recomputed along the fixed directions: hit
/// points (t and barycentrics from the moving vertices and the moving origin), normals, BSDF
/// values and cosines. Pdfs and MIS weights are computed from detached values: differentiating the
/// density of a detached sample would bias the estimate. NEE samples a light point but keeps only
/// its direction; the emitted radiance along it is constant, so it carries no derivative, and
/// there is no geometry term. Env-map radiance depends on direction only: zero derivative.
/// Paths that carry derivatives (T a dual, or a view that declares kDerivativeSampling: reverse
/// mode's probe) draw diffuse directions from a defensive mixture (kDerivativeDiffuseUniformShare,
/// bsdf.h), whose pdf their MIS weights use too; primal paths draw them from the cosine density.
///
/// Depth follows Mitsuba 3: max_depth counts path segments (1 = directly seen emitters,
/// 2 = direct illumination); -1 means unbounded, capped at kUnboundedDepthCap segments.

#include "qsil/area_lights.h"
#include "qsil/bsdf.h"
#include "qsil/dual.h"
#include "qsil/environment_light.h"
#include "qsil/integrators/surface_interaction.h"
#include "qsil/ray_tracer.h"
#include "qsil/rng.h"
#include "qsil/scene.h"

#include <optional>

namespace qsil {

/// Segment cap for max_depth = -1 (Russian roulette is off: it adds variance to gradients).
inline constexpr int kUnboundedDepthCap = 64;

/// What every path needs: scene, ray tracer and the light samplers. Built once per render.
struct PathContext {
  const Scene* scene = nullptr;
  const RayTracer* tracer = nullptr;
  const EnvironmentLight* environment = nullptr;
  const AreaLights* area_lights = nullptr;
  int max_depth = 3;         ///< segments; already resolved (never -1)
  double p_environment = 0;  ///< probability that NEE samples the environment (else area lights)

  static int resolve_depth(int max_depth) { return max_depth < 0 ? kUnboundedDepthCap : max_depth; }
};

/// Counters of one thread's work (summed for the final report).
struct PathStats {
  uint64_t rays = 0;
  uint64_t boundary_traversals = 0;  ///< edge-forest traversals (boundary-term samples)
  uint64_t boundary_zero = 0;        ///< ...that contributed nothing (no edge, not a silhouette, occluded, f = 0)
  double boundary_seconds = 0;       ///< thread time spent in the boundary term
  PathStats& operator+=(const PathStats& o) {
    rays += o.rays;
    boundary_traversals += o.boundary_traversals;
    boundary_zero += o.boundary_zero;
    boundary_seconds += o.boundary_seconds;
    return *this;
  }
};

/// Power heuristic weight of a strategy with pdf a against one with pdf b (Veach 1997). Detached.
inline double power_heuristic(double a, double b) {
  if (!(a > 0)) return 0.0;
  if (!std::isfinite(a)) return 1.0;
  const double a2 = a * a, b2 = b * b;
  return a2 / (a2 + b2);
}

/// Solid-angle pdf with which NEE would have chosen direction `dir` toward an area-light point at
/// distance `dist` with unit normal `light_n` (0 for the back side). Detached.
inline double nee_area_pdf(const PathContext& ctx, double dist, const Vec3& dir, const Vec3& light_n) {
  const double cos_l = -light_n.dot(dir);
  if (!(cos_l > 0) || !ctx.area_lights || ctx.area_lights->empty()) return 0.0;
  return (1.0 - ctx.p_environment) * ctx.area_lights->pdf_area() * dist * dist / cos_l;
}

/// The BSDF of a surface interaction, with the shading frame over T.
template <class T>
struct ShadingPoint {
  const BSDFDesc* bsdf;
  FrameT<T> frame;    ///< shading frame over T (moves with the surface)
  Frame frame_value;  ///< its detached value (sampling happens here)
};

/// Smallest cosine between wo and the adapted shading normal (see make_shading_point).
inline constexpr double kShadingNormalMinCos = 1e-3;

/// The shading frame of a surface interaction seen from direction `wo_world` (toward the viewer).
/// Shading-normal adaptation: where wo lies above the geometric surface but below the
/// interpolated shading normal's horizon (near silhouettes of smooth meshes), a one-sided BSDF
/// would render black, and the border of that black fringe is a discontinuity that moves with
/// the geometry but lies on no mesh edge: no edge sampler can find it, and the boundary term
/// would see the fringe's black instead of the lit surface at a silhouette. The shading normal
/// is therefore bent toward the viewer just enough that wo stays above its horizon:
///   ns' = normalize(ns + k wo),  k = max(0, eps - ns.wo),
/// so ns'.wo >= eps/|ns + k wo| > 0. It depends on ns and wo only, both continuous across the
/// edges of a smooth-shaded mesh, so the image and its derivative stay continuous there (an
/// adaptation toward the geometric normal would jump at every edge with the normal). Only where
/// the geometric surface faces the viewer (ng.wo > 0): a one-sided surface seen from behind stays
/// black, and that changes only at silhouettes. A twosided BSDF seen from the back flips the
/// shading normal first (and the test uses |ng.wo|).
/// At a constant interaction (si.constant) the frame is computed in doubles and lifted.
/// `Dir`: Vec3 (a fixed direction), or Vec3T<T> (warped-area sampling's moving wo, warp_field.h;
/// constant wherever si is: make_interaction). Callers use make_shading_point.
template <class T, class Dir>
ShadingPoint<T> shading_point_toward(const PathContext& ctx, const SurfaceInteraction<T>& si, const Dir& wo_world) {
  const Vec3 wo_value = value(wo_world);
  if constexpr (!std::is_same_v<T, double>) {
    if (si.constant) {
      SurfaceInteraction<double> s;
      s.shape = si.shape;
      s.ng = value(si.ng);
      s.ns = value(si.ns);
      const ShadingPoint<double> sp = shading_point_toward(ctx, s, wo_value);
      FrameT<T> frame;
      frame.s = lift<T>(sp.frame.s);
      frame.t = lift<T>(sp.frame.t);
      frame.n = lift<T>(sp.frame.n);
      return ShadingPoint<T>{sp.bsdf, frame, sp.frame_value};
    }
  }
  const Shape& shape = ctx.scene->shapes[si.shape];
  const BSDFDesc* bsdf = &ctx.scene->bsdfs[shape.bsdf];
  Vec3T<T> ns = si.ns;
  const Vec3T<T> wo = direction_over<T>(wo_world);
  double gw = value(si.ng).dot(wo_value);
  if (gw < 0 && bsdf->twosided) {
    ns = -ns;
    gw = -gw;
  }
  if (gw > 0) {
    const T k = T(kShadingNormalMinCos) - ns.dot(wo);
    if (value(k) > 0) {
      using std::sqrt;
      const Vec3T<T> n = ns + wo * k;
      ns = n / sqrt(n.squaredNorm());
    }
  }
  return ShadingPoint<T>{bsdf, FrameT<T>(ns), Frame(value(ns))};
}

/// shading_point_toward a fixed viewer direction.
template <class T>
ShadingPoint<T> make_shading_point(const PathContext& ctx, const SurfaceInteraction<T>& si, const Vec3& wo_world) {
  return shading_point_toward(ctx, si, wo_world);
}

/// shading_point_toward a moving viewer direction (warped-area sampling).
template <class T>
requires(!std::is_same_v<T, double>) ShadingPoint<T> make_shading_point(const PathContext& ctx,
                                                                        const SurfaceInteraction<T>& si,
                                                                        const Vec3T<T>& wo_world) {
  return shading_point_toward(ctx, si, wo_world);
}

/// A path vertex's BSDF as the tracers use it: its shading point, the viewer direction wo in its
/// frame (over T, and detached), and f_s cos toward a world direction.
template <class T>
struct VertexBSDF {
  ShadingPoint<T> sp;
  Vec3T<T> wo;
  Vec3 wo_value;
  bool constant = false;  ///< the interaction is constant: evaluate in doubles and lift
  /// f_s cos toward world direction w (over T; in doubles, lifted, at a constant interaction
  /// toward a fixed direction). `Dir`: Vec3, or Vec3T<T> (a warped direction, warp_field.h).
  template <class Dir = Vec3>
  ColorT<T> toward(const Dir& w) const {
    if constexpr (!std::is_same_v<T, double> && std::is_same_v<Dir, Vec3>)
      if (constant) return lift<T>(bsdf_eval<double>(*sp.bsdf, sp.frame_value.to_local(w), wo_value));
    return bsdf_eval<T>(*sp.bsdf, sp.frame.to_local(direction_over<T>(w)), wo);
  }
};

/// The VertexBSDF of interaction `si` seen from world direction `wo_world` (toward the viewer):
/// make_shading_point, and wo in its frame (in doubles, lifted, at a constant interaction).
/// `Dir` as for shading_point_toward: Vec3, or Vec3T<T> (warped-area sampling).
template <class T, class Dir = Vec3>
VertexBSDF<T> vertex_bsdf(const PathContext& ctx, const SurfaceInteraction<T>& si, const Dir& wo_world) {
  const ShadingPoint<T> sp = shading_point_toward(ctx, si, wo_world);
  const Vec3T<T> wo =
      si.constant ? lift<T>(sp.frame_value.to_local(value(wo_world))) : sp.frame.to_local(direction_over<T>(wo_world));
  return VertexBSDF<T>{sp, wo, value(wo), si.constant};
}

/// True when direction `w` leaves the surface of `si` on the side opposite to the viewer
/// direction `wo_world` (a "sliver" direction, reachable only through a shading normal tilted
/// past the geometric one). Such rays pass through back faces (IgnoreSet::through_back_faces:
/// why is explained there); the test is on detached values.
template <class T>
bool leaves_below(const SurfaceInteraction<T>& si, const Vec3& wo_world, const Vec3& w) {
  const Vec3 ng = value(si.ng);
  return ng.dot(w) * ng.dot(wo_world) < 0;
}

/// The hook of a path vertex for estimators that add a term there (the boundary term); the primal
/// path tracer has none.
struct NoVertexHook {
  template <class... Args>
  void operator()(Args&&...) const {}
};

/// Radiance the environment sends along an escaped ray's direction `d`, weighted by MIS against
/// environment NEE when the ray was BSDF-sampled with solid-angle pdf `bsdf_pdf_prev` > 0.
inline Color escaped_radiance(const PathContext& ctx, const Vec3& d, double bsdf_pdf_prev) {
  if (!ctx.environment || !ctx.environment->present()) return Color::Zero();
  double w = 1.0;
  if (bsdf_pdf_prev > 0 && ctx.p_environment > 0)
    w = power_heuristic(bsdf_pdf_prev, ctx.p_environment * ctx.environment->pdf(d));
  return Color(ctx.environment->eval(d) * w);
}

/// One light sample of next-event estimation: the vertex's f_s cos toward the light (over T) and
/// the light's radiance times its MIS weight over its pdf (detached), so that the path adds
/// beta * f * weighted_radiance.
template <class T>
struct DirectLight {
  ColorT<T> f;
  Color weighted_radiance;
};

/// A direction toward a light, drawn by next-event estimation from a point: the environment (with
/// probability p_environment) or a point on the area lights. Invalid (valid false) when the light
/// sample is (zero pdf, or the area-light point is the point itself).
struct LightDirection {
  bool valid = false;
  bool environment = false;
  Vec3 wi = Vec3::Zero();          ///< unit, world, toward the light
  Color radiance = Color::Zero();  ///< environment: its radiance along wi
  double pdf = 0;                  ///< environment: p_environment times its solid-angle pdf
  AreaLights::Sample area;         ///< area lights: the sampled point
  double dist = 0;                 ///< area lights: |point - p|
};

/// Draws a LightDirection from point p (world) with four numbers: environment or area lights, the
/// point (two), the triangle. Every next-event estimator draws its light so.
inline LightDirection sample_light_direction(const PathContext& ctx, const Vec3& p, Sampler& sampler) {
  const bool use_env = ctx.p_environment > 0 && sampler.next() < ctx.p_environment;
  const Vec2 u = sampler.next2();
  const double u_tri = sampler.next();
  LightDirection ld;
  ld.environment = use_env;
  if (use_env) {
    const auto s = ctx.environment->sample(u);
    if (s.pdf > 0) {
      ld.valid = true;
      ld.wi = s.dir;
      ld.radiance = s.radiance;
      ld.pdf = ctx.p_environment * s.pdf;
    }
  } else if (ctx.area_lights && !ctx.area_lights->empty()) {
    ld.area = ctx.area_lights->sample(u, u_tri);
    const Vec3 to = ld.area.point - p;
    ld.dist = to.norm();
    if (ld.area.pdf_area > 0 && ld.dist > 0) {
      ld.valid = true;
      ld.wi = to / ld.dist;
    }
  }
  return ld;
}

/// Next-event estimation at a path vertex: draws four numbers (environment or area lights, the
/// point, the triangle), traces the shadow ray and returns the sample, or nothing when the light
/// sample is invalid, the BSDF is zero toward it or it is occluded. `wo_local` is the viewer
/// direction in the shading frame (detached); `bsdf_toward(w)` is f_s cos toward world direction
/// w. MIS: power heuristic against BSDF sampling, whose diffuse directions come from the path's
/// defensive share `uniform_share` (trace_path's: kDerivativeDiffuseUniformShare on paths that
/// carry derivatives, 0 on primal paths).
template <class T, class BsdfToward>
std::optional<DirectLight<T>> sample_direct_light(const PathContext& ctx, const SurfaceInteraction<T>& si,
                                                  const ShadingPoint<T>& sp, const Vec3& wo_world, const Vec3& wo_local,
                                                  const BsdfToward& bsdf_toward, double uniform_share, Sampler& sampler,
                                                  PathStats& stats) {
  const LightDirection ld = sample_light_direction(ctx, value(si.p), sampler);
  const Vec3& wi = ld.wi;
  Color Le = Color::Zero();
  double pdf_light = 0;
  Vec3 light_point = Vec3::Constant(kInf);  // finite for area lights: where the shadow ray ends
  if (ld.valid && ld.environment) {
    Le = ld.radiance;
    pdf_light = ld.pdf;
  } else if (ld.valid) {
    pdf_light = nee_area_pdf(ctx, ld.dist, wi, ld.area.normal);
    if (pdf_light > 0) {
      Le = ctx.area_lights->radiance(ld.area.shape, ld.area.normal, -wi);
      light_point = ld.area.point;
    }
  }
  if (!(pdf_light > 0 && (Le > 0).any())) return std::nullopt;
  const ColorT<T> f = bsdf_toward(wi);
  if (!(value(f) != 0).any()) return std::nullopt;
  ++stats.rays;
  // The shadow ray starts at the offset origin and stops short of the light's own triangle by a
  // relative margin, measured from that origin (measured from p, an offset toward the light could
  // reach the light itself).
  const Vec3 origin = spawn_origin(si, wi);
  const double tmax = light_point.allFinite() ? (light_point - origin).norm() * (1.0 - 1.0 / 4096.0) : kInf;
  IgnoreSet ignore;
  ignore.through_back_faces = leaves_below(si, wo_world, wi);
  if (ctx.tracer->occluded(origin, wi, tmax, ignore)) return std::nullopt;
  const double w = power_heuristic(pdf_light, bsdf_pdf(*sp.bsdf, sp.frame_value.to_local(wi), wo_local, uniform_share));
  return DirectLight<T>{f, Color(Le * (w / pdf_light))};
}

/// A camera ray: its direction (world frame, unit) and first hit.
struct CameraRay {
  Vec3 dir;
  Hit hit;
};

/// The camera ray of pixel (x, y) at offset u in [0, 1)^2 within the pixel (a sample's first two
/// numbers), traced with ctx.tracer from ctx.scene's camera and counted in stats.rays. Every
/// estimator opens a sample with it, so that they all place a sample alike.
inline CameraRay trace_camera_ray(const PathContext& ctx, int x, int y, const Vec2& u, PathStats& stats) {
  const Camera& cam = ctx.scene->camera;
  const Vec3 d = cam.direction(x + u.x(), y + u.y());
  ++stats.rays;
  return {d, ctx.tracer->intersect(cam.origin(), d)};
}

/// The point the next segment's hit is recomputed from (differentiable): the point p the ray left,
/// or, from an exact edge point (si.inward set), the offset origin `spawned` (spawn_origin), p
/// shifted by a constant, so its derivatives are p's. The edge point lies in the plane of its
/// edge's other face, so at a concave edge a ray recomputed from the point itself would meet that
/// face at t = 0, on the edge, instead of where the ray from inside the face meets it
/// (docs/design-notes.md, "Smooth shading" item 2).
template <class T>
Vec3T<T> continuation_origin(const SurfaceInteraction<T>& si, const Vec3& spawned) {
  const Vec3 p = value(si.p);
  return si.inward == Vec3::Zero() ? si.p : Vec3T<T>(si.p + lift<T>(Vec3(spawned - p)));
}

/// The ray a path starts or continues with: from `origin` (over T: it may move) in the fixed
/// direction `dir`, whose hit `first_hit` is already traced (so the caller can reuse it), after
/// `segments_before` segments (0 for a camera ray), chosen by BSDF sampling with detached
/// solid-angle pdf `bsdf_pdf` (0: not BSDF-sampled, so emission found along it has weight 1).
template <class T>
struct PathRay {
  Vec3T<T> origin;
  Vec3 dir;
  Hit first_hit;
  int segments_before = 0;
  double bsdf_pdf = 0;
  /// Or null: the first segment's direction over T (attached camera hits, attached_camera.h), whose
  /// value is `dir`; the first hit and its viewer direction then move with it. The caller
  /// multiplies the radiance by the warp's Jacobian.
  const Vec3T<T>* moving_dir = nullptr;
};

/// The directions of a path are fixed (qsil's parametrization): trace_path's default `Warp`.
struct NoWarp {
  static constexpr bool enabled = false;
};

/// Radiance arriving at `ray.origin` from `ray.dir` along a path, plus its forward-mode derivative
/// when T is a dual. At every vertex that may still scatter (segments < max_depth),
/// `hook(si, sp, wo_local_value, beta, segments_so_far, sampler, stats, L)` may add to L.
/// `warp`: NoWarp (directions fixed), or warped-area sampling's DirectionWarp (warp_field.h):
/// every direction sampled at a vertex (toward the next vertex, toward a light) is then moved
/// by `warp(si, wo_world, w, stats)`, the path continues along the warped direction (the next
/// hit, the next vertex's wo) and its contribution is multiplied by the warp's Jacobian. The
/// ray's own direction is `warp.first_direction(ray.dir)` (its Jacobian is the caller's).
/// A view with `attach(si, hit, origin, dir, scatters)` (reverse mode) is called after each hit;
/// its returning false ends the path there, with L as it stands. `View::kDerivativeSampling`,
/// where declared, chooses the diffuse sampling (file comment) instead of T.
template <class View, class Hook = NoVertexHook, class Warp = NoWarp>
ColorT<typename View::Real> trace_path(const PathContext& ctx, const View& view,
                                       const PathRay<typename View::Real>& ray, Sampler& sampler, PathStats& stats,
                                       const Hook& hook = {}, const Warp& warp = {}) {
  using T = typename View::Real;
  // Paths that carry derivatives draw diffuse directions from the defensive mixture
  // (kDerivativeDiffuseUniformShare, bsdf.h); primal paths from the cosine density. A double
  // view that stands in for a derivative path (View::kDerivativeSampling, reverse mode's probe)
  // samples as the derivative path would, so that both trace the same path.
  constexpr bool derivative_sampling = [] {
    if constexpr (requires { View::kDerivativeSampling; }) return View::kDerivativeSampling;
    return !std::is_same_v<T, double>;
  }();
  constexpr double uniform_share = derivative_sampling ? kDerivativeDiffuseUniformShare : 0.0;
  ColorT<T> L = lift<T>(Color::Zero().eval());
  ColorT<T> beta = lift<T>(Color::Ones().eval());
  Vec3T<T> o = ray.origin;
  Vec3 d = ray.dir;
  Vec3T<T> d_warped;  // d moving with theta (Warp::enabled only)
  if constexpr (Warp::enabled) d_warped = warp.first_direction(ray.dir);
  Hit hit = ray.first_hit;
  double bsdf_pdf_prev = ray.bsdf_pdf;
  for (int seg = ray.segments_before + 1;; ++seg) {
    // ---- The ray escaped: it sees the environment (MIS against environment NEE).
    if (!hit.valid()) {
      if (ctx.environment && ctx.environment->present()) L += beta * lift<T>(escaped_radiance(ctx, d, bsdf_pdf_prev));
      break;
    }
    const bool first_moves = !Warp::enabled && ray.moving_dir && seg == ray.segments_before + 1;
    SurfaceInteraction<T> si = Warp::enabled ? make_interaction(view, hit, o, d_warped, ctx.tracer->local_origin())
                               : first_moves
                                   ? make_interaction(view, hit, o, *ray.moving_dir, ctx.tracer->local_origin())
                                   : make_interaction(view, hit, o, d, ctx.tracer->local_origin());
    // A view with a tape (reverse mode, qsil/integrators/reverse.h) records the hit and gives its
    // point and shading normal derivative slots of their own; the other views have no attach().
    // attach() returns false to end the path here (L as it stands): reverse mode's probe stops at
    // the first hit that needs derivatives.
    if constexpr (requires { view.attach(si, hit, value(o), d, true); }) {
      if (!view.attach(si, hit, value(o), d, seg < ctx.max_depth)) break;
      si.constant = false;  // attach() gives the point derivative slots of its own
    }
    // A ray grazing a triangle's plane has no well-defined intersection: end the path rather than
    // propagate a NaN (never reached with Embree's own hits in practice).
    if (!value(si.p).allFinite() || !value(si.ns).allFinite()) break;
    const Shape& shape = ctx.scene->shapes[si.shape];
    const Vec3 ng = value(si.ng);
    const Vec3 wo_world = -d;

    // ---- Emission found by this segment (MIS against area-light NEE).
    if (shape.is_emitter && ng.dot(wo_world) > 0) {
      double w = 1.0;
      if (bsdf_pdf_prev > 0) w = power_heuristic(bsdf_pdf_prev, nee_area_pdf(ctx, value(si.t), d, ng));
      L += beta * lift<T>(Color(shape.radiance * w));
    }
    if (seg >= ctx.max_depth) break;

    const VertexBSDF<T> vertex = Warp::enabled ? vertex_bsdf(ctx, si, Vec3T<T>(-d_warped))
                                 : first_moves ? vertex_bsdf(ctx, si, Vec3T<T>(-*ray.moving_dir))
                                               : vertex_bsdf(ctx, si, wo_world);
    const ShadingPoint<T>& sp = vertex.sp;
    const Vec3& wo_value = vertex.wo_value;
    // f_s cos toward w; under a warp, along the warped w and times the warp's Jacobian.
    const auto bsdf_toward = [&](const Vec3& w) -> ColorT<T> {
      if constexpr (Warp::enabled) {
        const auto warped = warp(si, wo_world, w, stats);
        return vertex.toward(warped.dir) * warped.jacobian;
      } else {
        return vertex.toward(w);
      }
    };
    hook(si, sp, wo_value, beta, seg, sampler, stats, L);

    // ---- Next-event estimation: keep only the sampled direction; re-evaluate along it.
    if (const auto direct =
            sample_direct_light(ctx, si, sp, wo_world, wo_value, bsdf_toward, uniform_share, sampler, stats))
      L += beta * direct->f * lift<T>(direct->weighted_radiance);

    // ---- BSDF sampling: a detached direction, then the throughput re-evaluated over T.
    const BSDFSample bs = bsdf_sample(*sp.bsdf, wo_value, sampler.next2(), uniform_share);
    if (!bs.valid || !(bs.pdf > 0)) break;
    const Vec3 wi = sp.frame_value.to_world(bs.wi).normalized();
    ColorT<T> f;
    if constexpr (Warp::enabled) {
      const auto warped = warp(si, wo_world, wi, stats);
      f = vertex.toward(warped.dir) * warped.jacobian;
      d_warped = warped.dir;
    } else {
      f = bsdf_toward(wi);
    }
    beta = beta * f / T(bs.pdf);
    if ((value(beta) == 0).all()) break;
    bsdf_pdf_prev = bs.pdf;
    ++stats.rays;
    IgnoreSet ignore;
    ignore.through_back_faces = leaves_below(si, wo_world, wi);
    const Vec3 spawned = spawn_origin(si, wi);
    hit = ctx.tracer->intersect(spawned, wi, kInf, ignore);
    o = continuation_origin(si, spawned);
    d = wi;
  }
  return L;
}

}  // namespace qsil
