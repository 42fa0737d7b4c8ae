#pragma once
/// @file render_setup.h
/// What every estimator of one scene sets up once and reuses in every run, in forward and in
/// reverse mode: one bundle, so that the estimators cannot set up differently.

#include "boundary_setup.h"
#include "light_setup.h"
#include "primary_boundary.h"
#include "qsil/integrators/boundary_term.h"
#include "qsil/integrators/path_tracer.h"
#include "qsil/ray_tracer.h"
#include "qsil/scene.h"

namespace qsil {

/// The ray tracer, the lights and the path context over them (built at construction), and, when
/// the estimator samples the boundary term, its edge structure and sampler (`boundary`), its
/// per-vertex context (`boundary_ctx`) and the camera's primary edges (`primary`), filled by
/// set_up_boundary_term (boundary_setup.h); empty otherwise. `ctx` and `boundary_ctx` point into the
/// bundle, so it is neither copied nor moved.
struct RenderSetup {
  explicit RenderSetup(const Scene& scene) : tracer(scene), lights(scene), ctx(lights.context(scene, tracer)) {}
  RenderSetup(const RenderSetup&) = delete;
  RenderSetup& operator=(const RenderSetup&) = delete;

  RayTracer tracer;
  LightSetup lights;
  PathContext ctx;
  BoundarySetup boundary;
  BoundaryContext boundary_ctx;
  PrimaryEdges primary;
};

/// The primal image of samples [first, first + count) of every pixel over `setup`'s ray tracer and
/// lights, as `qsil render`: film channels R, G, B of `layout` (FilmLayout(0)), the counters of
/// run_pixels in `r`. The primal estimator and ReverseEstimator::render both render so, hence the
/// same image for the same scene and seed.
void render_primal(const Scene& scene, const RenderSetup& setup, const FilmLayout& layout,
                   const RenderOptions& options, int first, int count, RenderResult& r);

}  // namespace qsil
