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
  /// The path context over these lights and `tracer`: the scene's resolved max depth; NEE picks
  /// the environment with probability 1/2 when the scene has both kinds of light.
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

}  // namespace qsil
