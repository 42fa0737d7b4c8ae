#pragma once
/// @file boundary_setup.h
/// The set-up of a boundary method (docs/architecture.md §7): the edge structure its sampler
/// needs and nothing else, the secondary edge sampler, and the importance inputs of the boundary
/// term. Used by the gradient and reverse estimators (estimator.cpp, reverse.cpp) and by tests that drive the boundary
/// term directly.

#include "primary_boundary.h"
#include "qsil/edgetree/contour_set.h"
#include "qsil/edgetree/edge_forest.h"
#include "qsil/edgetree/edge_sampler.h"
#include "qsil/environment_sun.h"
#include "qsil/integrators/boundary_term.h"
#include "qsil/integrators/estimator.h"
#include "qsil/integrators/method.h"
#include "qsil/scene.h"

#include <memory>
#include <optional>
#include <vector>

namespace qsil {

/// A boundary method's structures: the scene's edge set (an EdgeForest for quadric and
/// quadric-box, fitted with quadrics only for quadric; a plain EdgeSet for vsphere,
/// vsphere-solid and uniform), for quadric in a scene with a glossy BSDF the meshes' adjacency for
/// contour sets, and the sampler over the edges.
struct BoundarySetup {
  std::unique_ptr<edgetree::EdgeSet> edges;        ///< edge set or forest (the sampler points into it)
  std::unique_ptr<edgetree::EdgeSampler> sampler;  ///< the method's secondary edge sampler
  const edgetree::EdgeForest* forest = nullptr;    ///< `edges` as a forest (quadric methods), else null
  /// Mesh adjacency for contour sets (Method::Quadric in a scene with a glossy BSDF), else null.
  std::unique_ptr<edgetree::ContourIndex> contours;
  /// The environment map's sun (find_environment_sun of the environment given to
  /// build_boundary_setup), a light of the light-aware importance (set_light_importance); none
  /// without one.
  std::optional<EnvironmentSun> sun;
  double seconds = 0;                              ///< wall time of the build
};

/// Builds the structures of `method` (one of kEdgeSamplingMethods, or Projective: the edge set
/// alone, no sampler) over every shape of `scene`
/// (a moving shading point sees static edges move too, docs/architecture.md §5), with the
/// segments of the intersection curves among the always-candidates unless `intersection_curves`
/// is false. The v-sphere tree's Hough origin is the camera centre. `environment` (null: none) gives
/// the sun (BoundarySetup::sun), which makes the quadric method build its contour index as an
/// area light does. The scene must outlive the result.
BoundarySetup build_boundary_setup(const Scene& scene, Method method, bool intersection_curves = true,
                                   const EnvironmentLight* environment = nullptr);

/// The importance inputs of the boundary term [QSS 3.6]: every rectangle emitter as a light
/// polygon weighted by the luminance of its radiance, every other emitter (a mesh) as a light
/// sphere that bounds its vertices (edgetree::LightSphere), the environment map's `sun` (if any)
/// as a light sphere far beyond the scene (sun_light_sphere), and the environment's weight
/// (luminance of its mean radiance without the sun's share; 1 when the scene has no light of
/// either kind and no environment, i.e. plain [QSS 3.5] importance); every
/// shape's emitted luminance (the outline of any emitter weighs it); and, from
/// context.velocities (set it first; none: no scale), each parameter's velocity scale.
void set_light_importance(const Scene& scene, const EnvironmentLight& environment,
                          const std::optional<EnvironmentSun>& sun, BoundaryContext& context);

/// The light sphere that stands for `sun` in the light-aware importance: centred at distance
/// D = kSunDistance x R along the sun's axis from the centre c of `scene_bounds` (R its half
/// diagonal), of radius D sin(half_angle) + R, so that from any point p of the box every
/// direction within the sun's cone meets it (the cone's ray from p runs parallel to the one from
/// c, at most R from it), with the sun's radiance and no shape. False (`out` untouched) for an
/// empty or non-finite box, or one of zero size.
bool sun_light_sphere(const EnvironmentSun& sun, const Box3& scene_bounds, edgetree::LightSphere& out);

/// How far the sun's stand-in lies (sun_light_sphere), in half diagonals of the scene's box: its
/// parallax from the scene is at most 1 / kSunDistance radians, which its radius covers.
inline constexpr double kSunDistance = 1000.0;

/// Throws qsil::Error unless `sppi` (EstimatorConfig::sppi) is 0 (the method's
/// default) or in [1/1024, 1024].
void check_sppi(double sppi);

/// The sample rates of a gradient estimator (forward or reverse mode), checked before any set-up:
/// throws qsil::Error unless `sppi` passes check_sppi and `sppp` is in
/// (0, 1024] with its samples per index countable for `camera`'s image (primary_samples_per_index).
void check_sample_rates(const Camera& camera, double sppi, double sppp);

/// Fills the set-up report's edge-structure fields from a built boundary method: build time, edge
/// count, fitted and quadric node counts, `primary_edges`, and the structure's name ("edge forest
/// (dual box + quadrics)", "edge forest (dual box)", "edge set + uniform tables", "edge set +
/// v-sphere tree", "edge set + boundary segment tables").
void describe_boundary_setup(const BoundarySetup& boundary, Method method, int primary_edges, SetupReport& setup);

/// The boundary term of a run, set up once (what GradientEstimator and ReverseEstimator both do):
/// build_boundary_setup of `method` into `boundary`; `boundary_ctx` with its sampler, `velocities` (forward
/// mode's; null in reverse mode: velocity factor 1), `moving` (the shapes whose edges are eligible
/// at a static shading point), every shape eligible at a moving one, sppi traversals per
/// vertex (0: default_sppi of the method) and set_light_importance; `primary` =
/// find_primary_edges of the `moving` shapes (their visibility from the camera tested with
/// `tracer`); and describe_boundary_setup into `setup`. `moving` and `boundary_ctx.all` are extended with
/// the crossing groups of the edge set (edgetree::CrossingGroup: eligible where either of its
/// shapes is), and `primary` takes the extended vector. `intersection_curves`: as for
/// build_boundary_setup. `scene`, `tracer` and `velocities` must outlive the results.
void set_up_boundary_term(const Scene& scene, const RayTracer& tracer, Method method, const SceneVelocities* velocities,
                          const std::vector<bool>& moving, double sppi, const EnvironmentLight& environment,
                          BoundarySetup& boundary, BoundaryContext& boundary_ctx, PrimaryEdges& primary, SetupReport& setup,
                          bool intersection_curves = true);

/// Brings a boundary term set up by set_up_boundary_term up to date after the vertices of `scene`
/// moved (the same shapes and triangles: an optimiser's step; `tracer` already updated): an edge
/// forest is refitted (EdgeForest::refit) and built anew only when the refit refuses or advises
/// it (RefitReport::rebuild_advised); another method's edge set is built anew. A refitted
/// forest keeps its sampler (it reads the forest at every query) and refits its contour index
/// (ContourIndex::refit, which relinks the moved edges); both are attached to `boundary_ctx` with
/// the crossing groups' eligibility and the light importance, as set_up_boundary_term does, and
/// the primary edges are found anew. `boundary_ctx`'s velocities and sample rates are kept. If it
/// throws, `boundary` is unusable (ReverseEstimator::update then sets up anew at its next call).
/// Returns the refit's report (refitted false: built anew; reason "not an edge forest" for the
/// other methods).
edgetree::RefitReport update_boundary_term(const Scene& scene, const RayTracer& tracer, Method method,
                                           const std::vector<bool>& moving, const EnvironmentLight& environment,
                                           BoundarySetup& boundary, BoundaryContext& boundary_ctx, PrimaryEdges& primary,
                                           SetupReport& setup, bool intersection_curves = true);

}  // namespace qsil
