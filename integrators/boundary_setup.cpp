/// @file boundary_setup.cpp
/// See boundary_setup.h.

#include "boundary_setup.h"

#include "qsil/check.h"
#include "qsil/edgetree/quadric_sampler.h"
#include "qsil/edgetree/uniform_sampler.h"
#include "qsil/edgetree/vsphere_sampler.h"
#include "qsil/error.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <span>
#include <string>
#include <vector>

namespace qsil {
namespace {

/// Whether shape s is a quad area light of the light-aware importance (an emitting rectangle).
bool is_quad_light(const Shape& s) { return s.is_emitter && s.type == "rectangle" && s.mesh.positions.size() == 4; }

/// The sphere that stands for a mesh emitter in the light-aware importance (edgetree::LightSphere):
/// centred on its vertices' bounding box, through its farthest vertex (a bound, not the smallest).
edgetree::LightSphere light_sphere(const Shape& s, int index) {
  edgetree::LightSphere light;
  Eigen::AlignedBox3d box;
  for (const Vec3& v : s.mesh.positions) box.extend(v);
  light.centre = box.center();
  double r2 = 0;
  for (const Vec3& v : s.mesh.positions) r2 = std::max(r2, (v - light.centre).squaredNorm());
  light.radius = std::sqrt(r2);
  light.weight = luminance(s.radiance);
  light.shape = index;
  return light;
}

/// The contour index (the quadric method in a scene with a glossy BSDF or an area light) and the
/// sampler of an edge forest's method over `forest`, into `out` (both point into the forest; out.sun
/// set first).
void make_forest_sampler(const Scene& scene, Method method, std::span<const edgetree::ForestShapeInput> inputs,
                         const edgetree::EdgeForest& forest, BoundarySetup& out) {
  // Contour sets for narrow lobes and small area lights: the quadric method only (quadric-box
  // is the paper's ablation, kept as the paper traverses), in scenes with a glossy BSDF on some
  // shape or an area light (a quad or a mesh emitter, or the environment's sun:
  // set_light_importance's lights).
  const bool glossy = std::any_of(scene.shapes.begin(), scene.shapes.end(), [&](const Shape& s) {
    return s.bsdf >= 0 && scene.bsdfs[size_t(s.bsdf)].type == BSDFDesc::Type::RoughConductor;
  });
  const bool area_light =
      out.sun || std::any_of(scene.shapes.begin(), scene.shapes.end(), [](const Shape& s) { return s.is_emitter; });
  if (method == Method::Quadric && (glossy || area_light))
    out.contours = std::make_unique<edgetree::ContourIndex>(edgetree::ContourIndex::build(inputs, forest));
  out.sampler = std::make_unique<edgetree::QuadricEdgeSampler>(forest, node_test(method));
  out.forest = &forest;
}

/// What set_up_boundary_term and update_boundary_term do once `boundary` is built or refitted:
/// `boundary_ctx`'s sampler, contour index, eligibility (`moving` and every shape, extended with
/// the crossing groups) and light importance; the primary edges; the set-up report.
void attach_boundary(const Scene& scene, const RayTracer& tracer, Method method, const std::vector<bool>& moving,
                     const EnvironmentLight& environment, const BoundarySetup& boundary, BoundaryContext& boundary_ctx,
                     PrimaryEdges& primary, SetupReport& setup) {
  boundary_ctx.sampler = boundary.sampler.get();
  boundary_ctx.contours = boundary.contours.get();
  boundary_ctx.moving = moving;
  boundary_ctx.all.assign(scene.shapes.size(), true);
  // A crossing group moves where either of its shapes does.
  for (const edgetree::CrossingGroup& g : boundary.edges->crossing_groups()) {
    const size_t id = size_t(g.id);
    if (boundary_ctx.moving.size() <= id) boundary_ctx.moving.resize(id + 1, false);
    if (boundary_ctx.all.size() <= id) boundary_ctx.all.resize(id + 1, true);
    auto moves = [&](int s) { return s >= 0 && s < int(moving.size()) && moving[size_t(s)]; };
    boundary_ctx.moving[id] = moves(g.shape0) || moves(g.shape1);
  }
  set_light_importance(scene, environment, boundary.sun, boundary_ctx);
  primary = find_primary_edges(scene, *boundary.edges, boundary_ctx.moving, tracer, kPrimaryHiddenShare,
                               boundary_ctx.camera_hits);
  describe_boundary_setup(boundary, method, int(primary.edges.size()), setup);
  setup.attached_vertices = setup.moving_vertices = 0;
  for (size_t i = 0; i < scene.shapes.size() && i < moving.size(); ++i)
    if (moving[i]) setup.moving_vertices += scene.shapes[i].mesh.num_vertices();
  for (const std::vector<double>& a : primary.attachment.strength)
    setup.attached_vertices += int(std::count_if(a.begin(), a.end(), [](double v) { return v > 0; }));
  setup.static_primary_edges = primary.static_edges;
}

}  // namespace

BoundarySetup build_boundary_setup(const Scene& scene, Method method, bool intersection_curves,
                                   const EnvironmentLight* environment) {
  QSIL_CHECK_MSG(uses_edge_set(method), "no edge set for method " << method_name(method));
  const auto t0 = std::chrono::steady_clock::now();
  BoundarySetup out;
  if (environment) out.sun = find_environment_sun(*environment);
  const std::vector<edgetree::ForestShapeInput> inputs = edgetree::forest_inputs(scene);
  if (uses_edge_forest(method)) {
    // quadric-box uses the dual box only: its forest fits no quadric (the box test reads nothing
    // of it, so the samples are the same).
    edgetree::ForestOptions options;
    options.fit.fit_quadrics = uses_quadrics(method);
    options.intersection_curves = intersection_curves;
    auto forest = std::make_unique<edgetree::EdgeForest>(edgetree::EdgeForest::build(inputs, options));
    make_forest_sampler(scene, method, inputs, *forest, out);
    out.edges = std::move(forest);
  } else {
    edgetree::EdgeSetOptions options;
    options.intersection_curves = intersection_curves;
    out.edges = std::make_unique<edgetree::EdgeSet>(edgetree::EdgeSet::build(inputs, options));
    if (method == Method::Projective) {
      // No secondary edge sampler: its boundary sample space is built by the estimator
      // (integrators/projective_boundary.h), over these edges.
    } else if (method == Method::Uniform) {
      out.sampler = std::make_unique<edgetree::UniformEdgeSampler>(*out.edges);
    } else {
      // Li 2019: the Hough origin is the camera centre (docs/architecture.md §7).
      out.sampler = std::make_unique<edgetree::VSphereEdgeSampler>(*out.edges, scene.camera.origin(), vsphere_test(method));
    }
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

bool sun_light_sphere(const EnvironmentSun& sun, const Box3& scene_bounds, edgetree::LightSphere& out) {
  const double R = 0.5 * scene_bounds.diagonal();
  if (!(R > 0) || !std::isfinite(R) || !scene_bounds.center().allFinite()) return false;
  const double D = kSunDistance * R;
  out.centre = scene_bounds.center() + D * sun.axis;
  out.radius = D * std::sin(sun.half_angle) + R;
  out.weight = sun.radiance;
  out.shape = -1;
  return true;
}

void set_light_importance(const Scene& scene, const EnvironmentLight& environment,
                          const std::optional<EnvironmentSun>& sun, BoundaryContext& context) {
  context.lights.clear();
  context.light_spheres.clear();
  for (const Shape& s : scene.shapes) {
    if (s.is_emitter && !is_quad_light(s) && !s.mesh.positions.empty())
      context.light_spheres.push_back(light_sphere(s, int(&s - scene.shapes.data())));
    if (!is_quad_light(s)) continue;
    edgetree::LightPolygon light;
    for (int i = 0; i < 4; ++i) light.corners[size_t(i)] = s.mesh.positions[size_t(i)];
    light.normal = s.mesh.face_cross(0).normalized();
    light.weight = luminance(s.radiance);
    light.shape = int(&s - scene.shapes.data());
    context.lights.push_back(light);
  }
  context.emission.clear();
  for (const Shape& s : scene.shapes) context.emission.push_back(s.is_emitter ? luminance(s.radiance) : 0.0);
  context.velocity_scale.fill(0.0);
  if (context.velocities)
    for (int k = 0; k < context.velocities->num_params; ++k) {
      double vmax = 0;
      for (const auto& shape_v : context.velocities->position)
        for (const auto& v : shape_v) vmax = std::max(vmax, v.col(k).norm());
      context.velocity_scale[size_t(k)] = vmax > 0 ? 1.0 / vmax : 0.0;
    }
  context.env_weight = environment.present() ? luminance(environment.average_radiance()) : 0.0;
  edgetree::LightSphere sun_sphere;
  if (sun && sun_light_sphere(*sun, scene.bounds(), sun_sphere)) {
    context.light_spheres.push_back(sun_sphere);
    context.env_weight *= 1.0 - sun->share;  // the rest of the map
  }
  // Without any light: plain [QSS 3.5] importance.
  if (context.lights.empty() && context.light_spheres.empty() && context.env_weight == 0) context.env_weight = 1.0;
}

void check_sppi(double sppi) {
  // Beyond these a traversal's weight 1 / rate or its count overflows nothing yet, but no use
  // needs them: 1/1024 is one traversal in 1024 samples.
  if (sppi == 0) return;
  if (!(sppi >= 1.0 / 1024 && sppi <= 1024))
    throw Error("boundary samples per shading point must be 0 (the method's default) or in [1/1024, 1024] (got " +
                std::to_string(sppi) + ")");
}

void check_sample_rates(const Camera& camera, double sppi, double sppp) {
  primary_samples_per_index(camera.width, camera.height, sppp);  // throws if invalid
  check_sppi(sppi);
}

void describe_boundary_setup(const BoundarySetup& boundary, Method method, int primary_edges, SetupReport& setup) {
  setup.edge_seconds = boundary.seconds;
  setup.edges = int(boundary.edges->edges().size() + boundary.edges->always_edges().size());
  setup.primary_edges = primary_edges;
  setup.crossing_segments = int(boundary.edges->crossings().size());
  setup.crossing_seconds = boundary.edges->crossing_stats().seconds;
  setup.sun_share = boundary.sun ? boundary.sun->share : 0.0;
  setup.sun_half_angle_degrees = boundary.sun ? boundary.sun->half_angle * 180.0 / kPi : 0.0;
  if (boundary.forest) {
    for (const auto& st : boundary.forest->stats()) {
      setup.fitted_nodes += st.fitted;
      setup.quadric_nodes += st.quadrics;
    }
    setup.structure = uses_quadrics(method) ? "edge forest (dual box + quadrics)" : "edge forest (dual box)";
  } else {
    setup.structure = method == Method::Uniform      ? "edge set + uniform tables"
                      : method == Method::Projective ? "edge set + boundary segment tables"
                                                     : "edge set + v-sphere tree";
  }
}

void set_up_boundary_term(const Scene& scene, const RayTracer& tracer, Method method, const SceneVelocities* velocities,
                          const std::vector<bool>& moving, double sppi, const EnvironmentLight& environment,
                          BoundarySetup& boundary, BoundaryContext& boundary_ctx, PrimaryEdges& primary, SetupReport& setup,
                          bool intersection_curves) {
  boundary = build_boundary_setup(scene, method, intersection_curves, &environment);
  boundary_ctx.velocities = velocities;
  boundary_ctx.sppi = sppi > 0 ? sppi : default_sppi(method);
  boundary_ctx.split_speed = default_split_speed(method);
  attach_boundary(scene, tracer, method, moving, environment, boundary, boundary_ctx, primary, setup);
}

edgetree::RefitReport update_boundary_term(const Scene& scene, const RayTracer& tracer, Method method,
                                           const std::vector<bool>& moving, const EnvironmentLight& environment,
                                           BoundarySetup& boundary, BoundaryContext& boundary_ctx, PrimaryEdges& primary,
                                           SetupReport& setup, bool intersection_curves) {
  const auto t0 = std::chrono::steady_clock::now();
  edgetree::RefitReport report;
  report.reason = "not an edge forest";
  if (boundary.forest) {
    // The primary edges point into the forest's edges (the sampler reads the forest anew at
    // every query; the contour index is linked anew below).
    primary = {};
    auto& forest = static_cast<edgetree::EdgeForest&>(*boundary.edges);
    const std::vector<edgetree::ForestShapeInput> inputs = edgetree::forest_inputs(scene);
    report = forest.refit(inputs);
    if (!report.rebuild_advised()) {
      if (boundary.contours && !boundary.contours->refit(inputs, forest))
        *boundary.contours = edgetree::ContourIndex::build(inputs, forest);
      boundary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
  }
  if (report.rebuild_advised()) boundary = build_boundary_setup(scene, method, intersection_curves, &environment);
  attach_boundary(scene, tracer, method, moving, environment, boundary, boundary_ctx, primary, setup);
  return report;
}

}  // namespace qsil
