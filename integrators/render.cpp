/// @file render.cpp
/// Primal and gradient image loops; see render.h.

#include "qsil/integrators/render.h"

#include "qsil/edgetree/edge_forest.h"
#include "qsil/integrators/boundary_term.h"
#include "integrators/edge_sampler_factory.h"
#include "qsil/integrators/geometry_view.h"
#include "qsil/integrators/path_tracer.h"
#include "integrators/pixel_loop.h"
#include "integrators/primary_boundary.h"
#include "qsil/error.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <memory>
#include <chrono>

namespace qsil {

namespace {

int resolve_spp(const Scene& scene, const RenderOptions& o) {
  const int spp = o.spp > 0 ? o.spp : scene.camera.spp;
  if (spp <= 0) throw Error("spp must be positive (got " + std::to_string(spp) + ")");
  return spp;
}

/// Builds the light samplers and path context of a scene.
struct LightSetup {
  EnvironmentLight environment;
  AreaLights area_lights;
  explicit LightSetup(const Scene& scene) : environment(scene.environment), area_lights(scene) {}
  PathContext context(const Scene& scene, const RayTracer& tracer) const {
    PathContext ctx;
    ctx.scene = &scene;
    ctx.tracer = &tracer;
    ctx.environment = &environment;
    ctx.area_lights = &area_lights;
    ctx.max_depth = PathContext::resolve_depth(scene.max_depth);
    const bool env = environment.present(), area = !area_lights.empty();
    ctx.p_environment = env && area ? 0.5 : (env ? 1.0 : 0.0);
    return ctx;
  }
};

/// One estimator pass over all pixels: `sample(x, y, s, sampler, stats, out)` fills out[0..C)
/// for sample s of pixel (x, y).
template <class SampleFn>
RenderResult run_pixels(const Scene& scene, const RenderOptions& options, int channels, const std::string& label,
                        SampleFn&& sample, PathStats* total = nullptr) {
  RenderResult result;
  result.spp = resolve_spp(scene, options);
  const int W = scene.camera.width, H = scene.camera.height;
  result.film = Film(W, H, channels);
  tbb::enumerable_thread_specific<PathStats> stats;
  std::atomic<uint64_t> nonfinite{0};
  const auto t0 = std::chrono::steady_clock::now();
  for_each_pixel(W, H, options.threads, options.progress ? label : "", [&](int x, int y) {
    std::vector<double> out(channels);
    PathStats& st = stats.local();
    const uint64_t pixel = uint64_t(y) * W + x;
    for (int s = 0; s < result.spp; ++s) {
      Sampler sampler(options.seed, pixel, uint64_t(s));
      sample(x, y, s, sampler, st, out.data());
      bool finite = true;
      for (double v : out) finite = finite && std::isfinite(v);
      if (!finite) {
        nonfinite.fetch_add(1);
        std::fill(out.begin(), out.end(), 0.0);
      }
      result.film.add_sample(x, y, out.data());
    }
  });
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (const auto& st : stats) {
    result.rays += st.rays;
    if (total) {
      total->rays += st.rays;
      total->boundary_traversals += st.boundary_traversals;
      total->boundary_zero += st.boundary_zero;
      total->boundary_seconds += st.boundary_seconds;
    }
  }
  result.nonfinite = nonfinite.load();
  return result;
}

template <int N>
RenderResult render_gradient_n(const Scene& scene, const std::vector<ParameterSpec>& params, const RenderOptions& options,
                               const GradientOptions& gopt, GradientReport* report) {
  const SceneVelocities vel = compute_velocities(scene, params);
  const RayTracer tracer(scene);
  const LightSetup lights(scene);
  const PathContext ctx = lights.context(scene, tracer);
  const DualView<N> view{&scene, &vel};
  const int K = int(params.size());
  const Camera& cam = scene.camera;
  const Vec3 origin = cam.origin();
  // ---- The edge forest over every shape (a moving shading point sees static edges move too).
  edgetree::EdgeForest forest;
  std::unique_ptr<edgetree::EdgeSampler> edge_sampler;
  BoundaryContext bctx;
  const bool boundary = gopt.boundary != BoundaryMethod::None && vel.any_moving();
  if (boundary) {
    const auto t0 = std::chrono::steady_clock::now();
    forest = edgetree::EdgeForest::build(edgetree::forest_inputs(scene));
    edge_sampler = make_edge_sampler(gopt.boundary, scene, forest);
    if (report) report->forest_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    bctx.sampler = edge_sampler.get();
    bctx.velocities = &vel;
    bctx.moving = vel.moving;
    bctx.all.assign(scene.shapes.size(), true);
    bctx.samples_per_vertex = std::max(1, gopt.boundary_spp);
    // Light-aware importance [QSS 3.6]: every rectangle emitter, weighted by its radiance, and the
    // environment by its mean radiance.
    auto luminance = [](const Color& c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; };
    for (const Shape& s : scene.shapes) {
      if (!s.is_emitter || s.type != "rectangle" || s.mesh.positions.size() != 4) continue;
      edgetree::LightPolygon light;
      for (int i = 0; i < 4; ++i) light.corners[size_t(i)] = s.mesh.positions[size_t(i)];
      light.normal = s.mesh.face_cross(0).normalized();
      light.weight = luminance(s.radiance);
      bctx.lights.push_back(light);
    }
    bctx.env_weight = lights.environment.present() ? luminance(lights.environment.average_radiance()) : 0.0;
    if (bctx.lights.empty() && bctx.env_weight == 0) bctx.env_weight = 1.0;  // plain [QSS 3.5] importance
  }
  PathStats total;
  RenderResult r = run_pixels(scene, options, gradient_film_channels(K), "grad",
                    [&](int x, int y, int s, Sampler& sampler, PathStats& st, double* out) {
    const Vec2 u = sampler.next2();
    const Vec3 d = cam.direction(x + u.x(), y + u.y());
    ++st.rays;
    const Hit hit = tracer.intersect(origin, d);
    ColorT<Dual<N>> L;
    if (boundary) {
      // The boundary term draws from a stream of its own, so the path itself is the primal's.
      Sampler bsampler(options.seed, uint64_t(y) * cam.width + x, uint64_t(s), 1);
      const BoundaryHook<N> hook{&ctx, &bctx, &bsampler};
      L = trace_path(ctx, view, lift<Dual<N>>(origin), d, hit, 0, 0.0, sampler, st, hook);
    } else {
      L = trace_path(ctx, view, lift<Dual<N>>(origin), d, hit, 0, 0.0, sampler, st);
    }
    for (int c = 0; c < 3; ++c) out[c] = L[c].value();
    for (int k = 0; k < K; ++k) {
      for (int c = 0; c < 3; ++c) out[3 * (1 + k) + c] = L[c].derivatives()[k];
      out[3 * (1 + K) + k] = (out[3 * (1 + k)] + out[3 * (1 + k) + 1] + out[3 * (1 + k) + 2]) / 3.0;
    }
  }, &total);
  // ---- Primary silhouettes: one edge sample per pixel sample, splatted where it lands.
  if (boundary) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::vector<PrimaryEdge> edges = find_primary_edges(scene, forest, vel.moving);
    PathStats primary;
    add_primary_boundary(r.film, ctx, vel, edges, (long long)cam.width * cam.height * r.spp, r.spp, options.seed,
                         options.threads, primary);
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    r.seconds += dt;
    r.rays += primary.rays;
    total.boundary_traversals += primary.boundary_traversals;
    total.boundary_zero += primary.boundary_zero;
    total.boundary_seconds += dt * double(options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency());
  }
  if (report) {
    report->traversals = total.boundary_traversals;
    report->zero_traversals = total.boundary_zero;
    // Thread time in the boundary term, as a share of the pixel loop's wall time.
    const double threads = double(options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency());
    report->boundary_seconds = std::min(r.seconds, total.boundary_seconds / threads);
  }
  return r;
}

}  // namespace

RenderResult render_primal(const Scene& scene, const RenderOptions& options) {
  const RayTracer tracer(scene);
  const LightSetup lights(scene);
  const PathContext ctx = lights.context(scene, tracer);
  const PrimalView view{&scene};
  const Camera& cam = scene.camera;
  const Vec3 origin = cam.origin();
  return run_pixels(scene, options, 3, "render", [&](int x, int y, int s, Sampler& sampler, PathStats& st, double* out) {
    const Vec2 u = sampler.next2();
    const Vec3 d = cam.direction(x + u.x(), y + u.y());
    ++st.rays;
    const Hit hit = tracer.intersect(origin, d);
    const Color L = trace_path(ctx, view, origin, d, hit, 0, 0.0, sampler, st);
    for (int c = 0; c < 3; ++c) out[c] = L[c];
  });
}

std::vector<std::string> gradient_channel_names(int num_params) {
  std::vector<std::string> names{"R", "G", "B"};
  for (int k = 0; k < num_params; ++k)
    for (const char* c : {"R", "G", "B"}) names.push_back("dtheta" + std::to_string(k) + "." + c);
  return names;
}

int gradient_film_channels(int num_params) { return 3 * (1 + num_params) + num_params; }

ImageSum derivative_image_sum(const Film& film, int num_params, int k) {
  const int c = 3 * (1 + num_params) + k;
  ImageSum s;
  double var = 0;
  for (int y = 0; y < film.height(); ++y)
    for (int x = 0; x < film.width(); ++x) {
      s.sum += film.mean(c, x, y);
      const double se = film.standard_error(c, x, y);
      var += se * se;
    }
  s.standard_error = std::sqrt(var);
  return s;
}

double default_fd_step(const Scene& scene, const ParameterSpec& param) {
  switch (param.kind) {
    case ParameterSpec::Kind::Translate:
    case ParameterSpec::Kind::Vertex: return 1e-3 * scene.bounds().diagonal() / param.direction.norm();
    case ParameterSpec::Kind::Rotate:
    case ParameterSpec::Kind::Scale: return 1e-3;
  }
  return 1e-3;
}

RenderResult render_finite_differences(const Scene& scene, const std::vector<ParameterSpec>& params,
                                       const std::vector<double>& steps, const RenderOptions& options) {
  const int K = int(params.size());
  if (K == 0) throw Error("fd needs at least one --param");
  if (K > kMaxParameters) throw Error("at most 8 parameters per run (got " + std::to_string(K) + ")");
  if (steps.size() != params.size()) throw Error("fd: one step per parameter expected");
  for (double h : steps)
    if (!(h > 0) || !std::isfinite(h)) throw Error("fd: step h must be positive and finite (got " + std::to_string(h) + ")");
  // One scene, tracer and light setup per side of each parameter (lights move with their shapes).
  struct Side {
    Scene scene;
    std::unique_ptr<RayTracer> tracer;
    std::unique_ptr<LightSetup> lights;
    PathContext ctx;
  };
  std::vector<std::unique_ptr<Side>> sides;
  auto make_side = [&](Scene s) {
    auto side = std::make_unique<Side>();
    side->scene = std::move(s);
    side->tracer = std::make_unique<RayTracer>(side->scene);
    side->lights = std::make_unique<LightSetup>(side->scene);
    side->ctx = side->lights->context(side->scene, *side->tracer);
    return side;
  };
  sides.push_back(make_side(scene));
  for (int k = 0; k < K; ++k) {
    sides.push_back(make_side(displaced_scene(scene, params, k, +steps[k])));
    sides.push_back(make_side(displaced_scene(scene, params, k, -steps[k])));
  }
  const Camera& cam = scene.camera;
  const Vec3 origin = cam.origin();
  auto radiance = [&](const Side& side, Sampler sampler, PathStats& st, const Vec2& u, int x, int y) {
    const Vec3 d = cam.direction(x + u.x(), y + u.y());
    ++st.rays;
    const Hit hit = side.tracer->intersect(origin, d);
    return trace_path(side.ctx, PrimalView{&side.scene}, origin, d, hit, 0, 0.0, sampler, st);
  };
  return run_pixels(scene, options, gradient_film_channels(K), "fd",
                    [&](int x, int y, int s, Sampler& sampler, PathStats& st, double* out) {
    const Vec2 u = sampler.next2();
    // Common random numbers: every side continues from a copy of the same sampler state.
    const Color L0 = radiance(*sides[0], sampler, st, u, x, y);
    for (int c = 0; c < 3; ++c) out[c] = L0[c];
    for (int k = 0; k < K; ++k) {
      const Color Lp = radiance(*sides[1 + 2 * k], sampler, st, u, x, y);
      const Color Lm = radiance(*sides[2 + 2 * k], sampler, st, u, x, y);
      const Color dL = (Lp - Lm) / (2.0 * steps[k]);
      for (int c = 0; c < 3; ++c) out[3 * (1 + k) + c] = dL[c];
      out[3 * (1 + K) + k] = dL.mean();
    }
  });
}

BoundaryMethod parse_boundary_method(const std::string& name) {
  if (name == "none") return BoundaryMethod::None;
  if (name == "quadric") return BoundaryMethod::Quadric;
  if (name == "quadric-box") return BoundaryMethod::QuadricBox;
  if (name == "vsphere") return BoundaryMethod::VSphere;
  if (name == "vsphere-solid") return BoundaryMethod::VSphereSolid;
  if (name == "uniform") return BoundaryMethod::Uniform;
  throw Error("--boundary '" + name +
              "': unsupported (supported: quadric, quadric-box, vsphere, vsphere-solid, uniform, none)");
}

RenderResult render_gradient(const Scene& scene, const std::vector<ParameterSpec>& params, const RenderOptions& options,
                             const GradientOptions& gopt, GradientReport* report) {
  const size_t K = params.size();
  if (K == 0) throw Error("grad needs at least one --param");
  if (K == 1) return render_gradient_n<1>(scene, params, options, gopt, report);
  if (K == 2) return render_gradient_n<2>(scene, params, options, gopt, report);
  if (K <= 4) return render_gradient_n<4>(scene, params, options, gopt, report);
  if (K <= 8) return render_gradient_n<8>(scene, params, options, gopt, report);
  throw Error("at most 8 parameters per run (got " + std::to_string(K) + ")");
}

}  // namespace qsil
