#pragma once
/// @file light_setup.h
/// The light samplers of a scene and the path context over them (shared by the estimators of
/// estimator.cpp and reverse.cpp).

#include "qsil/area_lights.h"
#include "qsil/environment_light.h"
#include "qsil/integrators/path_tracer.h"
#include "qsil/ray_tracer.h"
#include "qsil/scene.h"

namespace qsil {

/// The environment and area-light samplers of a scene, built once per estimator.
struct LightSetup {
  EnvironmentLight environment;
  AreaLights area_lights;
  explicit LightSetup(const Scene& scene) : environment(scene.environment), area_lights(scene) {}
  /// The path context over these lights and `tracer` (see context_over).
  PathContext context(const Scene& scene, const RayTracer& tracer) const {
    return context_over(scene, tracer, environment, area_lights);
  }
  /// The path context over `environment` and `area_lights` (which must outlive it) and `tracer`:
  /// the scene's resolved max depth; NEE picks the environment with probability 1/2 when the scene
  /// has both kinds of light. For estimators whose scenes share one environment (finite
  /// differences: the displaced scenes move shapes, never the environment).
  static PathContext context_over(const Scene& scene, const RayTracer& tracer, const EnvironmentLight& environment,
                                  const AreaLights& area_lights) {
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

}  // namespace qsil
