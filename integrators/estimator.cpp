/// @file estimator.cpp
/// The three kinds of estimator (primal, gradient, finite differences) behind Estimator; see
/// qsil/integrators/estimator.h.

#include "qsil/integrators/estimator.h"

#include "attached_control.h"
#include "forest_guide_training.h"
#include "pixel_loop.h"
#include "projective_boundary.h"
#include "qsil/check.h"
#include "qsil/error.h"
#include "qsil/integrators/attached_camera.h"
#include "qsil/integrators/boundary_hook.h"
#include "qsil/integrators/geometry_view.h"
#include "qsil/integrators/path_tracer.h"
#include "qsil/integrators/regularized_tracer.h"
#include "qsil/integrators/warp_field.h"
#include "render_setup.h"
#include "vertex_recorder.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>

namespace qsil {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// Worker threads of a run: options.threads, or every core of the current arena.
double thread_count(const RenderOptions& o) {
  return double(o.threads > 0 ? o.threads : tbb::this_task_arena::max_concurrency());
}

}  // namespace

void render_primal(const Scene& scene, const RenderSetup& setup, const FilmLayout& layout,
                   const RenderOptions& options, int first, int count, RenderResult& r) {
  const Camera& cam = scene.camera;
  const Vec3 origin = cam.origin();
  const PrimalView view{&scene};
  PathStats total;
  run_pixels(
      cam, layout, options, first, count, "render",
      [&](int x, int y, int, Sampler& sampler, PathStats& st, double* out) {
        const CameraRay ray = trace_camera_ray(setup.ctx, x, y, sampler.next2(), st);
        const Color L = trace_path(setup.ctx, view, {origin, ray.dir, ray.hit}, sampler, st);
        for (int c = 0; c < 3; ++c) out[layout.primal(c)] = L[c];
      },
      r, total);
}

namespace {

/// The radiance of one camera sample under regularised visibility (regularized_tracer.h): the
/// sample's first two numbers place it in the pixel, as trace_camera_ray does.
template <class View>
ColorT<typename View::Real> regularized_camera_sample(const RegularizedContext& rc, const View& view, int x, int y,
                                                      const Vec2& u, Sampler& sampler, PathStats& st) {
  using T = typename View::Real;
  const Camera& cam = rc.path->scene->camera;
  return trace_regularized_path(rc, view, lift<T>(cam.origin()), cam.direction(x + u.x(), y + u.y()), sampler, st);
}

/// The regularised primal image (film channels R, G, B).
void render_regularized(const Scene& scene, const RegularizedContext& rc, const FilmLayout& layout,
                        const RenderOptions& options, int first, int count, RenderResult& r) {
  const PrimalView view{&scene};
  PathStats total;
  run_pixels(
      scene.camera, layout, options, first, count, "render",
      [&](int x, int y, int, Sampler& sampler, PathStats& st, double* out) {
        const Vec2 u = sampler.next2();
        const Color L = regularized_camera_sample(rc, view, x, y, u, sampler, st);
        for (int c = 0; c < 3; ++c) out[layout.primal(c)] = L[c];
      },
      r, total);
}

/// The regularisation of `config` when it is enabled (for Method::Regularized it must be).
std::optional<Regularization> regularization_of(const EstimatorConfig& config) {
  if (config.method == Method::Regularized && !config.params.empty() && !config.regularization.enabled())
    throw Error("regularized: the blur width must be positive (Regularization::for_scene)");
  if (!config.regularization.enabled()) return std::nullopt;
  const Regularization& r = config.regularization;
  if (!std::isfinite(r.width)) throw Error("regularized: the blur width must be finite");
  return r;
}

}  // namespace

// ---- The interface of the three kinds

class Estimator::Impl {
 public:
  Impl(const Scene& scene, EstimatorConfig config)
      : scene(scene), config(std::move(config)), layout(int(this->config.params.size())) {}
  virtual ~Impl() = default;
  /// Renders samples [first, first + count) into `r` (film, counters).
  virtual void run(const RenderOptions& options, int first, int count, RenderResult& r) const = 0;

  const Scene& scene;
  EstimatorConfig config;
  FilmLayout layout;
  SetupReport setup;
  std::vector<double> steps;  ///< finite differences only
};

namespace {

/// The primal image (`qsil render`): film channels R, G, B.
class PrimalEstimator final : public Estimator::Impl, private RenderSetup {
 public:
  PrimalEstimator(const Scene& s, EstimatorConfig c) : Impl(s, std::move(c)), RenderSetup(s) {
    if (const auto reg = regularization_of(config)) near.emplace(s, *reg);
  }
  void run(const RenderOptions& options, int first, int count, RenderResult& r) const override {
    if (near)
      render_regularized(scene, {&ctx, &*near}, layout, options, first, count, r);
    else
      render_primal(scene, *this, layout, options, first, count, r);
  }

 private:
  std::optional<SoftScene> near;  ///< regularised visibility only
};

/// Primal + interior term in forward mode (duals of size N) + the boundary term of the method
/// (`qsil grad`).
template <int N>
class GradientEstimator final : public Estimator::Impl, private RenderSetup {
 public:
  GradientEstimator(const Scene& s, EstimatorConfig c)
      : Impl(s, std::move(c)), RenderSetup(s), vel(compute_velocities(s, config.params)) {
    // ---- The boundary method's structures, only when something moves.
    if (uses_edge_set(config.method) && vel.any_moving()) {
      boundary_ctx.camera_hits = config.camera_hits;
      set_up_boundary_term(s, tracer, config.method, &vel, vel.moving, config.sppi, lights.environment,
                           boundary, boundary_ctx, primary, setup, config.intersection_curves);
      if (primary.attached && config.camera_control_spp > 0) {
        const auto t0 = Clock::now();
        setup.control_pixels = set_attached_control(ctx, primary.attachment, config.camera_control_spp);
        setup.control_seconds = seconds_since(t0);
        setup.seconds += setup.control_seconds;
      }
      // Projective sampling: no secondary edge sampler, its boundary sample space instead.
      if (config.method == Method::Projective) {
        projective = make_projective_edges(*boundary.edges, boundary_ctx.moving);
        const auto t0 = Clock::now();
        PathStats training;
        if (config.projective_guiding.octree) {
          long long seeds = 0;
          guide = train_projected_guide(ctx, vel, *projective, config.projective_guiding, 0, training, &seeds);
          char buf[192];
          std::snprintf(buf, sizeof buf,
                        " + octree guide (%d leaves from %lld projected seeds, %g seed paths per pixel, %.3f s)",
                        guide.cells(), seeds, config.projective_guiding.seeds, seconds_since(t0));
          setup.structure += buf;
        } else if (config.projective_guiding.resolution > 0) {
          guide = train_segment_guide(ctx, vel, *projective, config.projective_guiding, 0, training);
          char buf[160];
          std::snprintf(buf, sizeof buf, " + grid guide (%d^3 cells, %g training segments per pixel, %.3f s)",
                        guide.resolution(), config.projective_guiding.training, seconds_since(t0));
          if (guide.resolution() > 0) setup.structure += buf;  // none for an empty sample space
        }
      }
    }
    if (config.forest_guiding.training > 0 && boundary.forest && boundary.sampler) train_forest_guide();
    if (config.method == Method::WarpedArea && vel.any_moving()) {
      warped = true;  // no structure: every direction is warped (warp_field.h)
      setup.structure = "warped-area sampling (" + std::to_string(config.warped_area.rays) + " auxiliary rays)";
    }
    if (config.method == Method::Regularized) {
      near.emplace(s, *regularization_of(config));
      setup.structure = "near-triangle BVH (regularized, reach " + std::to_string(near->query().reach()) + ")";
    }
  }

  void run(const RenderOptions& options, int first, int count, RenderResult& r) const override {
    const Camera& cam = scene.camera;
    const Vec3 origin = cam.origin();
    const DualView<N> view{&scene, &vel};
    const int K = layout.num_params();
    const bool with_boundary = bool(boundary.sampler);
    // A fractional boundary rate draws a pixel's samples unalike (boundary_traversals): that
    // fraction of them makes one more traversal, stratum 1 of the film.
    const double fraction = with_boundary ? boundary_ctx.sppi - std::floor(boundary_ctx.sppi) : 0.0;
    tbb::enumerable_thread_specific<edgetree::EdgeChoiceScratch> scratch;  // one per worker thread
    tbb::enumerable_thread_specific<TopSamples> largest{TopSamples(options.largest_samples)};
    if (near && options.largest_samples > 0)
      throw Error("regularized: the largest samples' paths are not traced for this method");
    if (warped && options.largest_samples > 0)
      throw Error("was: the largest samples' paths are not traced for this method");
    if (config.method == Method::Projective && options.largest_samples > 0)
      throw Error("projective: the largest samples' paths are not traced for this method");
    const RegularizedContext rc{&ctx, near ? &*near : nullptr};
    PathStats total;
    run_pixels(
        cam, layout, options, first, count, "grad",
        [&](int x, int y, int s, Sampler& sampler, PathStats& st, double* out) {
          const Vec2 u = sampler.next2();
          ColorT<Dual<N>> L;
          const uint64_t pixel = uint64_t(y) * cam.width + x;
          const int traversals =
              with_boundary ? boundary_traversals(boundary_ctx.sppi, options.seed, pixel, uint64_t(s)) : 0;
          const CameraRay ray = near ? CameraRay{} : trace_camera_ray(ctx, x, y, u, st);
          if (near) {
            L = regularized_camera_sample(rc, view, x, y, u, sampler, st);
          } else if (warped) {
            // The auxiliary rays and the pixel border draw from streams of their own, so they
            // leave the path's decisions unchanged.
            Sampler aux(options.seed, pixel, uint64_t(s), stream::kWasAuxiliary),
                border(options.seed, pixel, uint64_t(s), stream::kWasBorder);
            L = warped_pixel_sample(ctx, view, config.warped_area, x, y, ray, sampler, aux, border, st);
          } else {
            const AttachedCameraRay<N> attached = camera_ray_form(ray, Vec2(x + u.x(), y + u.y()), x, y);
            const PathRay<Dual<N>> path_ray{lift<Dual<N>>(origin), ray.dir, ray.hit, 0, 0, attached.moving_dir()};
            if (traversals > 0) {
              Sampler bsampler = boundary_stream(options.seed, pixel, uint64_t(s));
              const BoundaryHook<N> hook{{&ctx, &boundary_ctx, &bsampler, traversals, &scratch.local()}};
              L = trace_path(ctx, view, path_ray, sampler, st, hook);
            } else {
              L = trace_path(ctx, view, path_ray, sampler, st);
            }
            attached.apply_jacobian(L);
          }
          for (int c = 0; c < 3; ++c) out[layout.primal(c)] = L[c].value();
          for (int k = 0; k < K; ++k) {
            for (int c = 0; c < 3; ++c) out[layout.derivative(k, c)] = L[c].derivatives()[k];
            out[layout.derivative_mean(k)] =
                (out[layout.derivative(k, 0)] + out[layout.derivative(k, 1)] + out[layout.derivative(k, 2)]) / 3.0;
          }
          if (options.largest_samples > 0) {
            int kmax = 0;
            for (int k = 1; k < K; ++k)
              if (std::abs(out[layout.derivative_mean(k)]) > std::abs(out[layout.derivative_mean(kmax)])) kmax = k;
            if (std::isfinite(out[layout.derivative_mean(kmax)]))
              largest.local().offer(x, y, s, kmax, out[layout.derivative_mean(kmax)]);
          }
          // Stratum 1: the samples that made the rate's fractional traversal (Film::standard_error).
          return fraction > 0 && traversals > int(boundary_ctx.sppi) ? 1 : 0;
        },
        r, total, fraction);
    if (options.largest_samples > 0) trace_largest(options, largest, r);
    // ---- Primary silhouettes: sppp edge samples per pixel sample, splatted where they land;
    // projective sampling's boundary segments (sppi per pixel sample) after them, alike.
    if (boundary.edges) {
      const auto t0 = Clock::now();
      PathStats primary_stats;
      add_primary_boundary(r.film, ctx, vel, primary, config.sppp, first, count, options.seed,
                           options.threads, primary_stats, options.part, options.parts,
                           options.parts > 1 ? &r.splats : nullptr);
      // A run in parts draws all of them in its last part: merged in order (merge_part), every
      // splat sum is then formed in the whole run's order, primary splats first.
      if (projective && options.part == options.parts - 1)
        r.nonfinite +=
            add_projective_boundary(r.film, ctx, vel, *projective, guide, boundary_ctx.sppi, first, count, options.seed,
                                    options.threads, primary_stats, 0, 1, options.parts > 1 ? &r.splats : nullptr);
      const double dt = seconds_since(t0);
      r.seconds += dt;
      r.rays += primary_stats.rays;
      total.boundary_traversals += primary_stats.boundary_traversals;
      total.boundary_zero += primary_stats.boundary_zero;
      total.boundary_seconds += dt * thread_count(options);
    }
    r.traversals = total.boundary_traversals;
    r.zero_traversals = total.boundary_zero;
    // Thread time in the boundary term, as a share of the run's wall time.
    r.boundary_seconds = std::min(r.seconds, total.boundary_seconds / thread_count(options));
  }

 private:
  /// The forest guide of the edge choice (forest_guiding.h): config.forest_guiding.rounds
  /// training passes (forest_guide_pass), the guide retrained on all records after each; its
  /// size and time appended to setup.structure.
  void train_forest_guide() {
    const ForestGuiding& fg = config.forest_guiding;
    const auto t0 = Clock::now();
    forest_guide = std::make_unique<edgetree::ForestGuide>(*boundary.forest, fg.guide);
    boundary_ctx.guide = forest_guide.get();
    std::vector<edgetree::GuideRecord> records;
    PathStats training;
    for (int round = 0; round < fg.rounds; ++round) {
      const std::vector<edgetree::GuideRecord> pass =
          forest_guide_pass<N>(ctx, boundary_ctx, vel, fg.training, round, 0, training);
      records.insert(records.end(), pass.begin(), pass.end());
      forest_guide->train(records);
    }
    char buf[224];
    std::snprintf(buf, sizeof buf,
                  " + forest guide (%d slots to depth %d, %d cells of %d^3 learnt from %zu records, %d x %d "
                  "training spp, %.3f s)",
                  forest_guide->slots(), fg.guide.depth, forest_guide->occupied_cells(), fg.guide.resolution,
                  records.size(), fg.rounds, fg.training, seconds_since(t0));
    setup.structure += buf;
  }

  /// The samples kept by the threads' `largest`, largest first, each retraced from its own streams
  /// with the boundary term recorded beside the path, not added to it
  /// (qsil/integrators/sample_trace.h), into r.largest.
  void trace_largest(const RenderOptions& options, const tbb::enumerable_thread_specific<TopSamples>& largest,
                     RenderResult& r) const {
    TopSamples all(options.largest_samples);
    for (const TopSamples& t : largest) all.merge(t);
    r.largest = all.sorted();
    const Camera& cam = scene.camera;
    const DualView<N> view{&scene, &vel};
    for (SampleTrace& trace : r.largest) {
      Sampler sampler(options.seed, uint64_t(trace.y) * cam.width + trace.x, uint64_t(trace.sample));
      PathStats st;
      const Vec2 u = sampler.next2();
      const CameraRay ray = trace_camera_ray(ctx, trace.x, trace.y, u, st);
      const AttachedCameraRay<N> attached =
          camera_ray_form(ray, Vec2(trace.x + u.x(), trace.y + u.y()), trace.x, trace.y);
      const VertexRecorder<N> recorder{&trace, trace.param};
      const PathRay<Dual<N>> path_ray{lift<Dual<N>>(cam.origin()), ray.dir, ray.hit, 0, 0, attached.moving_dir()};
      const uint64_t pixel = uint64_t(trace.y) * cam.width + trace.x;
      const int traversals =
          boundary.sampler ? boundary_traversals(boundary_ctx.sppi, options.seed, pixel, uint64_t(trace.sample)) : 0;
      ColorT<Dual<N>> L;
      if (traversals > 0) {
        // The boundary term's own stream and traversals, as run() drew them: the same edge points.
        Sampler bsampler = boundary_stream(options.seed, pixel, uint64_t(trace.sample));
        edgetree::EdgeChoiceScratch scratch;
        const BoundaryPointRecorder<N> points{{&ctx, &boundary_ctx, &bsampler, traversals, &scratch},
                                              &trace,
                                              trace.param};
        L = trace_path(ctx, view, path_ray, sampler, st, BothHooks<VertexRecorder<N>, BoundaryPointRecorder<N>>{recorder, points});
      } else {
        L = trace_path(ctx, view, path_ray, sampler, st, recorder);
      }
      recorder.finish(L);
      attached.apply_jacobian(L);
      recorder.jacobian(L);
    }
  }

  /// The camera ray of a sample at film position `film` in pixel (px, py): attached
  /// (attached_camera_ray) when the primary term carries the attached flux, else fixed.
  AttachedCameraRay<N> camera_ray_form(const CameraRay& ray, const Vec2& film, int px, int py) const {
    if (primary.attached) return attached_camera_ray<N>(scene, vel, primary.attachment, ray, film, px, py);
    return AttachedCameraRay<N>::detached(ray.dir);
  }

  SceneVelocities vel;
  std::optional<SoftScene> near;  ///< Method::Regularized only
  bool warped = false;            ///< Method::WarpedArea with something moving
  std::optional<ProjectiveEdges> projective;  ///< Method::Projective with something moving
  SegmentGuide guide;                         ///< ...and its guide (uniform: unguided)
  /// The quadric methods' forest guide (boundary_ctx.guide points to it), or null: unguided.
  std::unique_ptr<edgetree::ForestGuide> forest_guide;
};

/// Central finite differences with common random numbers (`qsil fd`): the primal scene and, per
/// parameter, two displaced copies, each with its own ray tracer and lights (lights move with
/// their shapes), set up once.
class FiniteDifferenceEstimator final : public Estimator::Impl {
 public:
  FiniteDifferenceEstimator(const Scene& s, EstimatorConfig c)
      : Impl(s, std::move(c)), environment(std::make_unique<EnvironmentLight>(s.environment)) {
    const int K = layout.num_params();
    steps = config.fd_steps.empty() ? fd_steps(s, config.params, {}) : config.fd_steps;
    if (int(steps.size()) != K) throw Error("fd: one step per parameter expected");
    for (double h : steps)
      if (!(h > 0) || !std::isfinite(h))
        throw Error("fd: step h must be positive and finite (got " + std::to_string(h) + ")");
    // Every side's ray tracer uses the primal scene's local origin: static geometry is then
    // rounded to float alike on every side (no spurious motion of ulp size between them).
    const Vec3 local_origin = embree_local_origin(s);
    const std::optional<Regularization> reg = regularization_of(config);
    sides.push_back(std::make_unique<Side>(s, local_origin, reg, *environment));
    for (int k = 0; k < K; ++k) {
      sides.push_back(std::make_unique<Side>(displaced_scene(s, config.params, k, +steps[size_t(k)]), local_origin, reg,
                                             *environment));
      sides.push_back(std::make_unique<Side>(displaced_scene(s, config.params, k, -steps[size_t(k)]), local_origin, reg,
                                             *environment));
    }
    setup.structure = std::to_string(sides.size()) + " scenes (primal and displaced), each with a ray tracer";
  }

  void run(const RenderOptions& options, int first, int count, RenderResult& r) const override {
    const int K = layout.num_params();
    const Camera& cam = scene.camera;
    const Vec3 origin = cam.origin();
    auto radiance = [&](const Side& side, Sampler sampler, PathStats& st, const Vec2& u, int x, int y) {
      if (side.near)
        return regularized_camera_sample({&side.ctx, &*side.near}, PrimalView{&side.scene},
                                         x, y, u, sampler, st);
      const CameraRay ray = trace_camera_ray(side.ctx, x, y, u, st);
      return trace_path(side.ctx, PrimalView{&side.scene}, {origin, ray.dir, ray.hit}, sampler, st);
    };
    PathStats total;
    run_pixels(
        cam, layout, options, first, count, "fd",
        [&](int x, int y, int, Sampler& sampler, PathStats& st, double* out) {
          const Vec2 u = sampler.next2();
          // Common random numbers: every side continues from a copy of the same sampler state.
          const Color L0 = radiance(*sides[0], sampler, st, u, x, y);
          for (int c = 0; c < 3; ++c) out[layout.primal(c)] = L0[c];
          for (int k = 0; k < K; ++k) {
            const Color Lp = radiance(*sides[size_t(1 + 2 * k)], sampler, st, u, x, y);
            const Color Lm = radiance(*sides[size_t(2 + 2 * k)], sampler, st, u, x, y);
            const Color dL = (Lp - Lm) / (2.0 * steps[size_t(k)]);
            for (int c = 0; c < 3; ++c) out[layout.derivative(k, c)] = dL[c];
            out[layout.derivative_mean(k)] = dL.mean();
          }
        },
        r, total);
  }

 private:
  /// One side of a difference: a scene, its tracer and area lights (an emitter may be the shape
  /// that moves), the environment shared by every side (parameters move shapes only, so every
  /// side's environment is the primal scene's; one per side built 2K + 1 copies of a map's tables:
  /// docs/experiments/2026-11-29-huge-pages.md, "Finite differences"), and with regularised
  /// visibility its SoftScene.
  struct Side {
    Side(Scene s, const Vec3& local_origin, const std::optional<Regularization>& reg,
         const EnvironmentLight& environment)
        : scene(std::move(s)),
          tracer(scene, local_origin),
          area_lights(scene),
          ctx(LightSetup::context_over(scene, tracer, environment, area_lights)) {
      if (reg) near.emplace(scene, *reg);
    }
    Scene scene;
    RayTracer tracer;
    AreaLights area_lights;
    PathContext ctx;
    std::optional<SoftScene> near;
  };
  std::unique_ptr<const EnvironmentLight> environment;  ///< the primal scene's, shared by the sides
  std::vector<std::unique_ptr<Side>> sides;
};

/// The implementation of `config` (its kind, and for gradients the dual size N).
std::unique_ptr<Estimator::Impl> make_impl(const Scene& scene, EstimatorConfig config) {
  if (config.params.empty()) return std::make_unique<PrimalEstimator>(scene, std::move(config));
  check_parameter_count(config.params.size());
  if (config.method == Method::FiniteDifferences)
    return std::make_unique<FiniteDifferenceEstimator>(scene, std::move(config));
  const int K = int(config.params.size());
  return with_dual_size(K, [&](auto n) -> std::unique_ptr<Estimator::Impl> {
    return std::make_unique<GradientEstimator<decltype(n)::value>>(scene, std::move(config));
  });
}

}  // namespace

// ---- EstimatorConfig, RenderResult, SetupReport

EstimatorConfig EstimatorConfig::primal() { return {}; }

EstimatorConfig EstimatorConfig::gradient(std::vector<ParameterSpec> params, Method method, double sppi,
                                          double sppp) {
  EstimatorConfig c;
  c.params = std::move(params);
  c.method = method;
  c.sppi = sppi;
  c.sppp = sppp;
  return c;
}

EstimatorConfig EstimatorConfig::finite_differences(std::vector<ParameterSpec> params, std::vector<double> steps) {
  EstimatorConfig c;
  c.params = std::move(params);
  c.method = Method::FiniteDifferences;
  c.fd_steps = std::move(steps);
  return c;
}

void RenderResult::merge(const RenderResult& other) {
  film.merge(other.film);
  first_sample = std::min(first_sample, other.first_sample);
  spp += other.spp;
  seconds += other.seconds;
  rays += other.rays;
  nonfinite += other.nonfinite;
  boundary_seconds += other.boundary_seconds;
  traversals += other.traversals;
  zero_traversals += other.zero_traversals;
  if (!other.largest.empty()) {
    // Both lists hold the largest of their runs; the merged run keeps as many as the longer one.
    TopSamples top(int(std::max(largest.size(), other.largest.size())));
    for (const SampleTrace& s : largest) top.offer(s);
    for (const SampleTrace& s : other.largest) top.offer(s);
    largest = top.sorted();
  }
}

std::string SetupReport::describe() const {
  char buf[640], crossings[96] = "", sun[112] = "", attached[176] = "";
  if (crossing_segments > 0)
    std::snprintf(crossings, sizeof crossings, ", %d intersection-curve segments (%.3f s)", crossing_segments,
                  crossing_seconds);
  if (sun_share > 0)
    std::snprintf(sun, sizeof sun,
                  ", the environment's sun (%.2f deg, %.0f %% of its power) a light of the edge choice",
                  sun_half_angle_degrees, 100.0 * sun_share);
  if (attached_vertices > 0)
    std::snprintf(attached, sizeof attached,
                  ", camera hits attached at %d of %d moving vertices (%d static primary edges)", attached_vertices,
                  moving_vertices, static_primary_edges);
  if (attached_vertices > 0 && control_pixels > 0) {
    const size_t used = std::strlen(attached);
    std::snprintf(attached + used, sizeof attached - used, ", a control variate at %d pixels (%.3f s)", control_pixels,
                  control_seconds);
  }
  std::snprintf(buf, sizeof buf, "%s: %d edges, %d fitted nodes (%d with quadrics), %d primary edges%s%s%s, %.3f s",
                structure.c_str(), edges, fitted_nodes, quadric_nodes, primary_edges, crossings, sun, attached,
                seconds);
  return buf;
}

// ---- Estimator

Estimator::Estimator(const Scene& scene, EstimatorConfig config) {
  if (!config.params.empty() && config.method != Method::FiniteDifferences && config.method != Method::None &&
      config.method != Method::Regularized && config.method != Method::WarpedArea && !uses_edge_set(config.method))
    throw Error("method " + std::string(method_name(config.method)) + " cannot estimate derivatives");
  if (config.method == Method::WarpedArea) check_warped_area_sampling(config.warped_area);
  if (config.method == Method::Projective) check_projective_guiding(config.projective_guiding);
  check_forest_guiding(config.forest_guiding);
  check_camera_control_spp(config.camera_control_spp);
  if (config.forest_guiding.training > 0 && !config.params.empty() && config.method != Method::Quadric &&
      config.method != Method::QuadricBox)
    throw Error("forest guide: method " + std::string(method_name(config.method)) +
                " has no edge forest to guide (quadric, quadric-box)");
  check_sample_rates(scene.camera, config.sppi, config.sppp);
  const auto t0 = Clock::now();
  impl_ = make_impl(scene, std::move(config));
  impl_->setup.seconds = seconds_since(t0);
}

Estimator::~Estimator() = default;
Estimator::Estimator(Estimator&&) noexcept = default;
Estimator& Estimator::operator=(Estimator&&) noexcept = default;

int sample_range_count(const RenderOptions& options, const Camera& camera) {
  const int count = options.spp > 0 ? options.spp : camera.spp;
  if (count <= 0) throw Error("spp must be positive (got " + std::to_string(count) + ")");
  if (options.first_sample < 0)
    throw Error("the first sample index must be >= 0 (got " + std::to_string(options.first_sample) + ")");
  return count;
}

RenderResult Estimator::run(const RenderOptions& options) const {
  const int count = sample_range_count(options, impl_->scene.camera);
  if (options.parts < 1 || options.part < 0 || options.part >= options.parts)
    throw Error("part " + std::to_string(options.part) + " of " + std::to_string(options.parts) +
                " parts: expected 0 <= part < parts");
  RenderResult r;
  impl_->run(options, options.first_sample, count, r);
  QSIL_DCHECK(r.film.channels() == impl_->layout.channels());
  return r;
}

const FilmLayout& Estimator::layout() const { return impl_->layout; }
const EstimatorConfig& Estimator::config() const { return impl_->config; }
const SetupReport& Estimator::setup() const { return impl_->setup; }
const std::vector<double>& Estimator::fd_steps() const { return impl_->steps; }

// ---- finite-difference steps

double default_fd_step(const Scene& scene, const ParameterSpec& param) {
  const double displacement = 1e-3 * scene.bounds().diagonal();
  // The largest speed |dx/dtheta| over the shape's vertices (world units per unit of theta).
  const std::vector<Vec3>& positions = scene.shapes[size_t(param.shape)].mesh.positions;
  double speed = 0;
  for (size_t i = 0; i < positions.size(); ++i)
    speed = std::max(speed, vertex_velocity(param, int(i), positions[i]).norm());
  // A rotation or scale that moves no vertex (every vertex on the axis or at the centre): 1e-3.
  return speed > 0 && std::isfinite(displacement / speed) ? displacement / speed : 1e-3;
}

std::vector<double> fd_steps(const Scene& scene, const std::vector<ParameterSpec>& params,
                             const std::vector<double>& h) {
  std::vector<double> steps;
  for (size_t k = 0; k < params.size(); ++k) {
    if (h.empty())
      steps.push_back(default_fd_step(scene, params[k]));
    else if (h.size() == 1)
      steps.push_back(h[0]);
    else if (h.size() == params.size())
      steps.push_back(h[k]);
    else
      throw Error("--h: give one value or one per --param (" + std::to_string(params.size()) + ")");
  }
  return steps;
}

}  // namespace qsil
