#pragma once
/// @file reverse.h
/// Reverse mode: the gradient of a scalar loss with respect to every vertex position of chosen
/// shapes (docs/architecture.md §13), for the inverse-rendering loop of [QSS §5.5]. The loss is
///   L = sum over pixels x and channels c of w_c(x) I_c(x),
/// w an adjoint image (for an L2 loss sum (I - I_target)^2: w = 2 (I - I_target)). The estimate
/// is that of `qsil grad` in the same fixed-direction parametrization, read backwards:
/// - interior term: each camera path records the hits on chosen shapes that scatter on a tape;
///   the point p and the shading normal ns of each get derivative slots of their own (duals of
///   12 entries: two hits per pass; a longer path is replayed with the same random numbers for
///   the next two, Vicini et al. 2021 "Path Replay Backpropagation"). Their adjoints
///   (sum_c w_c dL_c/dslot) are carried back to the triangle's three vertex positions and three
///   vertex normals through the local Jacobian of the hit (make_interaction over 18-entry duals,
///   the ray origin held fixed: its own dependence is in the earlier slots); vertex-normal
///   adjoints reach the positions through the area-weighted normals (vertex_normals_adjoint);
/// - secondary boundary term: a sample on edge (v0, v1) at t with weight W (throughput x BSDF x
///   jump / pdf) adds W g (1 - t) to v0 and W g t to v1 (g = (w0 x w1)/|w_t|^3,
///   boundary_term.h), and -W g . dp/dslot to the slots of the moving shading point p;
/// - primary boundary term: the same for the camera's edge samples, weighted by the adjoint of
///   the pixel each lands in (for_each_primary_sample);
/// - attached camera hits (ReverseConfig::camera_hits, attached_camera.h): the first pass of a
///   path whose camera hit is attached gives the camera direction derivative slots of its own (the
///   second hit's; that pass then holds one hit), and the warp's local Jacobian over the hit
///   triangle's vertex positions (attached_camera_warp with a unit velocity per coordinate)
///   carries their adjoint, and (L - c) times the Jacobian's, to them; the primary term adds the
///   attached flux's adjoint to the vertices of the triangles its sides hit
///   (for_each_attached_side).
/// The edge sampler's importance has no velocities (velocity_factor 1): the per-vertex gradient
/// has a parameter per vertex. Eligible edges: those of chosen shapes at a static p, every
/// shape's at a p that moves (a chosen-shape hit at or before it).
/// Deterministic for a seed whatever the thread count: per 16 x 16 tile, sums in pixel order;
/// tiles, then primary chunks, are added in order.

#include "qsil/integrators/estimator.h"
#include "qsil/integrators/method.h"
#include "qsil/scene.h"

#include <memory>
#include <string>
#include <vector>

namespace qsil {

/// What reverse mode differentiates and how.
struct ReverseConfig {
  std::vector<int> shapes;          ///< indices into Scene::shapes whose vertex positions are differentiated
  Method method = Method::Quadric;  ///< boundary term: an edge-sampling method, or Method::None (interior only)
  double sppi = 0;          ///< EstimatorConfig::sppi (0: the method's default)
  /// Primary boundary-term edge samples per pixel sample (EstimatorConfig::sppp).
  double sppp = kDefaultSppp;
  /// Sample the intersection curves where surfaces cross (EstimatorConfig::intersection_curves).
  bool intersection_curves = true;
  /// Trace each sample's path in doubles first (a probe pass), and again with dual numbers only
  /// when it meets a chosen shape where it scatters; the dual pass then does the boundary term
  /// only from that hit on, the probe having done the vertices before it. The estimates are the
  /// same to rounding, from the same random numbers: a path that never meets a chosen shape has no
  /// interior derivative. false: every path with dual numbers, which costs more where the chosen
  /// shapes fill little of what the paths see (for tests and timing).
  bool probe_paths = true;
  /// Camera hits attached to the surface (EstimatorConfig::camera_hits, attached_camera.h), with
  /// the chosen shapes as the moving ones: the warp's local Jacobian (the hit triangle's three
  /// vertices) carries the warped direction's and the Jacobian's adjoints to them, and the primary
  /// term adds the attached flux's. Edge-sampling methods only (Method::None: detached, as in
  /// forward mode). The warp's Jacobian for one vertex holds the gradient of its barycentric, so
  /// the raw per-vertex gradient is noisier attached (2.75x on the teapot) while its smoothed
  /// (Large Steps) and whole-shape parts are less noisy
  /// (docs/experiments/2026-11-29-reverse-attached.md): Detached suits plain descent on x.
  CameraHits camera_hits = CameraHits::Adaptive;
  /// EstimatorConfig::camera_control_spp: the control variate's pre-pass, run by the constructor
  /// (and by an update() that sets up anew). Any other update() keeps the pixels' c: any c fixed
  /// before a run is unbiased (CameraAttachment::control), and one from earlier shapes saves an
  /// optimiser a pre-pass per step; only when there is none to keep (nothing was attached before,
  /// or the film's size changed) does the first update that attaches something run the pre-pass.
  /// 0 or at least 2 (check_camera_control_spp).
  int camera_control_spp = kAttachedControlSpp;
};

/// One reverse-mode run.
struct ReverseResult {
  int width = 0, height = 0, spp = 0;
  /// The primal image of the same paths, row-major RGB: image[3 (y width + x) + c].
  std::vector<double> image;
  /// sum_x,c w_c(x) I_c(x) over `image` (the loss of a linear adjoint; for an L2 loss the caller
  /// computes it from an image of its own).
  double loss = 0;
  /// dL/dx per vertex: gradient[i][v] for shape config.shapes[i], vertex v (scene units of L per
  /// scene unit of length).
  std::vector<std::vector<Vec3>> gradient;
  double seconds = 0;            ///< wall time of the run
  /// Ray queries of a sample's passes, its path's rays counted once: when a probe pass stopped,
  /// those of the dual pass, not the probe's (without replays, the count of a run without the
  /// probe; replayed passes after a probe skip the boundary term before the first chosen-shape hit).
  uint64_t rays = 0;
  uint64_t nonfinite = 0;        ///< samples with a NaN/inf value or gradient (dropped from every output, reported)
  uint64_t traversals = 0;       ///< boundary-term samples drawn (secondary and primary; as for rays)
  uint64_t zero_traversals = 0;  ///< ...that contributed nothing
  uint64_t replays = 0;          ///< extra passes of paths with more than two chosen-shape hits
  uint64_t probed = 0;           ///< samples whose probe pass was the whole sample (ReverseConfig::probe_paths)
};

/// What ReverseEstimator::update did.
struct ReverseUpdate {
  bool refitted = false;    ///< the edge forest was refitted (false: built anew, or no boundary term)
  std::string reason;       ///< why it was built anew (RefitReport::reason, or "box growth G", "N
                            ///< edges promoted"); empty when refitted
  double box_growth = 1.0;  ///< RefitReport::box_growth of the refit (1 when built anew)
  double seconds = 0;       ///< wall time of the whole update
  double edge_seconds = 0;  ///< ...of which the edge structure (refit or build, sampler, contour index)
};

/// Reverse mode set up for one scene (the scene must outlive it). Movable, not copyable.
class ReverseEstimator {
 public:
  /// Builds the ray tracer, lights, and for an edge-sampling method the boundary method's
  /// structures over every shape, the primary edges of the chosen shapes, their camera hits'
  /// attachment and its control variate (ReverseConfig::camera_control_spp). Throws qsil::Error
  /// for an empty or repeated shape list, a shape index out of range, a method that is neither
  /// an edge-sampling method nor none, a sppi or sppp out of range (check_sample_rates), or a
  /// control pre-pass neither 0 nor at least 2 spp (check_camera_control_spp).
  ReverseEstimator(const Scene& scene, ReverseConfig config);
  ~ReverseEstimator();
  ReverseEstimator(ReverseEstimator&&) noexcept;
  ReverseEstimator& operator=(ReverseEstimator&&) noexcept;

  /// Runs samples [options.first_sample, options.first_sample + spp) (spp = options.spp, or the
  /// scene's sample count when <= 0) with adjoint image `adjoint` (row-major RGB, width x height x
  /// 3 values: adjoint[3 (y width + x) + c] = w_c(x)). Throws qsil::Error when the adjoint has the
  /// wrong size ("adjoint image: expected W x H x 3 = N values (got M)") or a non-finite value
  /// ("adjoint image: non-finite weight at pixel (x, y)"), for an empty range, for
  /// options.parts > 1 (not supported), after a failed update(), and when the scene's meshes or
  /// film size changed since the set-up or the last update() (a hash of them: "call update()
  /// first").
  ReverseResult run(const std::vector<double>& adjoint, const RenderOptions& options) const;

  /// The primal image of samples [options.first_sample, options.first_sample + spp) over this
  /// set-up as of the last update(): the film of Estimator(scene, EstimatorConfig::primal()).run
  /// (options), bit for bit, without that estimator's set-up of a ray tracer and lights (an
  /// optimiser's primal render each step). Throws qsil::Error as run() does for an empty range,
  /// options.parts > 1, after a failed update(), or for a changed scene.
  RenderResult render(const RenderOptions& options) const;

  /// Brings the set-up up to date after the scene's meshes changed, at a fraction of a new
  /// set-up's cost when only vertex positions did (e.g. Python's set_vertices: an optimiser's
  /// step): the ray tracer's meshes taken anew (RayTracer::update_meshes), the area lights
  /// collected anew, the environment light kept,
  /// the edge forest refitted (update_boundary_term: built anew when the refit refuses or advises
  /// it) and the primary edges found anew. The estimates are as unbiased as a new estimator's;
  /// they differ from its estimates only in which edges the boundary term draws. When a shape's
  /// vertex or triangle count changed (a remeshing, Python's set_mesh) everything is set up anew,
  /// as by the constructor, and so when the scene's bounds moved the local origin a new ray tracer
  /// would take (embree_local_origin: the float geometry would round otherwise); a shape whose
  /// triangles changed with the same counts gets its forest built anew (the refit refuses it). If
  /// it throws (qsil::Error from Embree, out of memory), run() and render() refuse until an
  /// update() succeeds, which then sets up anew. Not to be called while run() or render() runs.
  ReverseUpdate update();

  /// The configuration given.
  const ReverseConfig& config() const;
  /// Set-up time and what was built (SetupReport::describe()).
  const SetupReport& setup() const;

  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// The shape indices of `ids` (Shape::id). Throws qsil::Error "--shape 'ID': no shape with this id
/// in FILE" for an unknown id and "--shape 'ID': given twice" for a repeated one.
std::vector<int> resolve_shapes(const Scene& scene, const std::vector<std::string>& ids);

}  // namespace qsil
