#pragma once
/// @file estimator.h
/// The estimator layer (the role of pbrt-v4's Integrator and of Mitsuba 3's integrator plugins):
/// an Estimator is set up once for a scene and what it estimates — the primal image, its
/// derivatives with a boundary method, or finite differences — and then run over ranges of sample
/// indices. Set-up builds what a run needs and nothing else (docs/architecture.md §2, step 4; the
/// edge structure as Method in method.h decides). Every command (`render`, `grad`, `fd`,
/// `reference`, `compare`), the progressive passes and the tools drive an Estimator.
///
/// Sample ranges: run() renders samples [first_sample, first_sample + spp) of every pixel. Sample
/// s of pixel p draws from the streams (seed, p, s) (docs/architecture.md §3 "Randomness"; which
/// samples make a fractional boundary traversal depends on (seed, p, s) too, through a rotation
/// drawn from (seed, p, 0, 3)), and the primary boundary term numbers its samples globally, a
/// whole number of chunks per sample index (add_primary_boundary in
/// integrators/primary_boundary.h), so that
/// - a run over [0, spp) draws the same samples however it is split into passes;
/// - runs over disjoint ranges draw independent samples, and their films merge
///   (RenderResult::merge) into a film of the union;
/// - runs over ranges that partition [0, spp) draw exactly the samples of the run over [0, spp):
///   the merged film equals its film up to the rounding of the sums.

#include "qsil/film.h"
#include "qsil/integrators/attached_camera.h"
#include "qsil/integrators/forest_guiding.h"
#include "qsil/integrators/method.h"
#include "qsil/integrators/projective_sampling.h"
#include "qsil/integrators/regularized_visibility.h"
#include "qsil/integrators/sample_trace.h"
#include "qsil/integrators/warped_area_sampling.h"
#include "qsil/parameters.h"
#include "qsil/scene.h"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace qsil {

/// Default primary boundary-term edge samples per pixel sample (EstimatorConfig::sppp):
/// the ratio at which the primary term's share of the variance and of the time balance on the
/// bundled scenes (docs/architecture.md §6 "How many primary samples").
inline constexpr double kDefaultSppp = 0.25;

/// What an estimator estimates.
struct EstimatorConfig {
  /// Parameters theta_k (1 to 8); empty: the primal image (method ignored).
  std::vector<ParameterSpec> params;
  /// With parameters: an edge-sampling method, Method::Projective or Method::None (primal +
  /// interior term + boundary term of that method), Method::Regularized or Method::WarpedArea (no
  /// boundary term: a blurred image, or warped directions), or Method::FiniteDifferences.
  Method method = Method::Quadric;
  /// Secondary boundary-term traversals per shading point (edge-sampling methods), on average over
  /// a pixel's samples: a fraction is taken by a stratified pick of samples (boundary_traversals
  /// in boundary_term.h). Method::Projective: boundary segments per pixel sample instead
  /// (integrators/projective_boundary.h). 0: the method's default (default_sppi), else in
  /// [1/1024, 1024].
  double sppi = 0;
  /// Primary boundary-term edge samples per pixel sample (edge-sampling methods; Mitsuba 3's
  /// `sppp` as a ratio to spp): ratio x W x H edge samples per sample index, rounded up to a whole
  /// chunk of 1024 (integrators/primary_boundary.h). In (0, 1024].
  double sppp = kDefaultSppp;
  /// Finite differences: one step h per parameter (units of theta); empty: default_fd_step each.
  std::vector<double> fd_steps;
  /// Edge-sampling methods: sample the intersection curves where surfaces cross
  /// (qsil/edgetree/intersection_curves.h) as discontinuities. Off only to measure what they add
  /// (`--no-intersection-curves`): where surfaces cross, the derivative is then biased.
  bool intersection_curves = true;
  /// Camera hits attached to the surface (qsil/integrators/attached_camera.h; `--camera-hits`):
  /// the interior term of a camera sample that hits a moving shape follows the surface point it
  /// hits, and the primary boundary term carries the matching flux. Methods with the primary
  /// boundary term only (every edge-sampling method and projective sampling). Adaptive: where the
  /// normal turns by more than a lobe width across a pixel; Attached: everywhere; Detached: the
  /// camera ray fixed.
  CameraHits camera_hits = CameraHits::Adaptive;
  /// Samples per pixel of the primal pre-pass that sets the attached camera hits' control variate
  /// (CameraAttachment::control, `--camera-control-spp`), at the pixels with attached hits; 0: no
  /// control (c = 0). 0 or at least 2: Estimator throws qsil::Error for any other value, whether or
  /// not a camera hit is attached (unused when none is).
  int camera_control_spp = kAttachedControlSpp;
  /// Regularised visibility (qsil/integrators/regularized_visibility.h; absolute, from
  /// Regularization::for_scene of the scene as loaded). Method::Regularized requires it enabled;
  /// enabled with Method::FiniteDifferences or without parameters, the differences and the image
  /// are those of the regularised image (the oracle of the regularised derivative); other methods
  /// ignore it.
  Regularization regularization;
  /// Method::WarpedArea: its auxiliary rays, kappa and exponent (warped_area_sampling.h).
  WarpedAreaSampling warped_area;
  /// Method::Projective: its guide (projective_sampling.h; resolution 0: unguided).
  ProjectiveGuiding projective_guiding;
  /// Method::Quadric and Method::QuadricBox: the forest guide of their edge choice
  /// (forest_guiding.h; training 0: unguided).
  ForestGuiding forest_guiding;

  /// The primal image.
  static EstimatorConfig primal();
  /// Primal + derivatives with `method` (an edge sampler or Method::None).
  static EstimatorConfig gradient(std::vector<ParameterSpec> params, Method method = Method::Quadric,
                                  double sppi = 0, double sppp = kDefaultSppp);
  /// Primal + central finite differences with steps `steps` (empty: defaults).
  static EstimatorConfig finite_differences(std::vector<ParameterSpec> params, std::vector<double> steps = {});
};

/// One run: which samples, which seed, how many threads.
struct RenderOptions {
  int spp = -1;          ///< samples per pixel of the run (its range's length); <= 0: the scene's sample_count
  int first_sample = 0;  ///< first sample index of the range [first_sample, first_sample + spp)
  uint64_t seed = 0;     ///< PCG32 seed; results are bit-identical for any thread count
  int threads = 0;       ///< 0 = all cores
  bool progress = true;  ///< progress bar on stderr (runs > 1 s)
  /// A run split into `parts` parts, one per process (qsil/integrators/distributed.h): this run is
  /// part `part` (0 <= part < parts). It renders every sample of the range, but only for the pixels
  /// of its part (Film::part_of: pixel index mod parts), and the part-th of `parts` contiguous
  /// shares of the primary boundary term's chunks, whose splats it returns in RenderResult::splats
  /// instead of adding them to its film. Combining parts 0, 1, ..., parts - 1 in order (merge_part)
  /// gives the whole run's result bit for bit. parts = 1: the whole run.
  int part = 0;
  int parts = 1;
  /// Gradient runs: keep the this many samples of largest |derivative| and trace their paths
  /// (RenderResult::largest; qsil/integrators/sample_trace.h). 0: none (no cost).
  int largest_samples = 0;
};

/// What a run produced and what it cost (set-up excluded: Estimator::setup()).
struct RenderResult {
  Film film{1, 1, FilmLayout()};
  int first_sample = 0;          ///< first sample index of the run
  int spp = 0;                   ///< samples per pixel (summed over merged runs)
  double seconds = 0;            ///< wall time of the pixel loop and the primary boundary term
  uint64_t rays = 0;             ///< ray queries issued
  uint64_t nonfinite = 0;        ///< samples with a NaN/inf value (replaced by 0 and reported)
  double boundary_seconds = 0;   ///< wall time attributed to the boundary term (thread-time share)
  uint64_t traversals = 0;       ///< boundary-term samples drawn (secondary and primary)
  uint64_t zero_traversals = 0;  ///< ...that contributed nothing
  /// Part runs (RenderOptions::parts > 1) only: the primary boundary term's splats of this part's
  /// chunks, in the order the whole run adds them to its film; they are not in `film`.
  std::vector<FilmSplat> splats;
  /// RenderOptions::largest_samples > 0, gradient runs only: the samples of largest |derivative|,
  /// largest first, each with its path (the interior term, vertex by vertex).
  std::vector<SampleTrace> largest;

  /// Adds the film and the counters of a run over a disjoint sample range of the same estimator
  /// (first_sample becomes the smaller one). Throws nothing; films must have the same layout and
  /// stratum fraction (a QSIL_CHECK: runs of one estimator always do).
  void merge(const RenderResult& other);
};

/// What set-up built and what it cost.
struct SetupReport {
  double seconds = 0;       ///< wall time of the whole set-up
  double edge_seconds = 0;  ///< of which the edge structure: edge set, forest fit, v-sphere tree, tables
  /// What was built for the derivatives: "none" (primal, interior term only, or nothing moves),
  /// "edge set + uniform tables", "edge set + v-sphere tree", "edge set + boundary segment tables", "edge forest (dual
  /// box)", "edge forest (dual box + quadrics)", or "N scenes (primal and displaced), ..." for finite differences.
  std::string structure = "none";
  int edges = 0;          ///< edges of the edge set (tree and always-candidate edges)
  int fitted_nodes = 0;   ///< forest nodes with a fitted dual bound (0 without a forest)
  int quadric_nodes = 0;  ///< ...of which carry a bounding quadric pair (0 unless `quadric`)
  int primary_edges = 0;  ///< discontinuity edges of moving shapes seen from the camera
  /// Segments of intersection curves among the edges (EdgeSet::crossings) and the wall time of
  /// finding them (broad and narrow phase; part of edge_seconds).
  int crossing_segments = 0;
  double crossing_seconds = 0;
  /// The environment map's sun as a light of the edge importance (find_environment_sun): its
  /// half-angle (degrees) and share of the map's power; share 0: none.
  double sun_half_angle_degrees = 0;
  double sun_share = 0;
  /// Attached camera hits (EstimatorConfig::camera_hits): vertices of moving shapes with a non-zero
  /// attachment strength, of all moving vertices, and the static shapes' primary edges sampled
  /// for the attached form's flux (0 when nothing is attached).
  int attached_vertices = 0, moving_vertices = 0, static_primary_edges = 0;
  /// Their control variate (EstimatorConfig::camera_control_spp): the pixels given one, and the
  /// pre-pass's wall time (part of `seconds`).
  int control_pixels = 0;
  double control_seconds = 0;
  /// One line: "STRUCTURE: E edges, F fitted nodes (Q with quadrics), P primary edges, T s", with
  /// ", C intersection-curve segments (T s)" before the time when there are any, and
  /// ", the environment's sun (A deg, S % of its power) a light of the edge choice" when one is,
  /// and ", camera hits attached at A of V moving vertices (S static primary edges)" when some are,
  /// followed by ", a control variate at P pixels (T s)" when it has one.
  std::string describe() const;
};

/// An estimator set up for one scene (see the file comment). Movable, not copyable; run() is
/// const and may be called any number of times (not concurrently: it parallelises itself).
class Estimator {
 public:
  /// Sets up `config` for `scene`, which must outlive the estimator. Throws qsil::Error for a
  /// parameter count outside 1..8 (check_parameter_count), a method that cannot estimate
  /// derivatives, sppp or sppi out of range (above), or finite-difference steps that are not positive and finite or not one per
  /// parameter. Uses the caller's TBB arena (forest fitting is parallel).
  Estimator(const Scene& scene, EstimatorConfig config);
  ~Estimator();
  Estimator(Estimator&&) noexcept;
  Estimator& operator=(Estimator&&) noexcept;

  /// Renders samples [options.first_sample, options.first_sample + spp) of every pixel (spp =
  /// options.spp, or the scene's sample_count when it is <= 0), or of its part options.part of
  /// options.parts. Throws qsil::Error when the range is empty or starts below 0, or the part is
  /// not 0 <= part < parts.
  RenderResult run(const RenderOptions& options) const;

  /// The channel layout of every film this estimator renders (K = params.size()).
  const FilmLayout& layout() const;
  /// What it estimates (as given; fd_steps() holds the steps in use).
  const EstimatorConfig& config() const;
  /// What set-up built and its time.
  const SetupReport& setup() const;
  /// The finite-difference steps in use (FiniteDifferences only; empty otherwise).
  const std::vector<double>& fd_steps() const;

  /// The implementation of one kind of estimator (primal, gradient, finite differences).
  class Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// The length of a run's sample range: options.spp, or the camera's sample count when it is <= 0.
/// Throws qsil::Error "spp must be positive (got N)" for an empty range and "the first sample
/// index must be >= 0 (got N)" for a negative start. Every estimator's run() checks its range here.
int sample_range_count(const RenderOptions& options, const Camera& camera);

/// Default finite-difference step h0 of a parameter (units of theta: scene units per unit
/// direction for translate and vertex, radians for rotate, relative for scale): the step that
/// moves the parameter's fastest vertex by 1e-3 of the scene's bounding-box diagonal, i.e. 1e-3
/// diagonal / max over the shape's vertices of |dx/dtheta| (|direction| for translate and
/// vertex, |axis x (x - centre)| for rotate, |x - centre| for scale). Every kind thus moves the
/// geometry, and its silhouettes on screen, by the same amount at h0: the blur of a step and its
/// variance where silhouettes cross pixels (both set by that motion) compare across kinds, and a
/// step study over h0 / 2^i holds for all of them at once (tools/references.py). 1e-3 when no
/// vertex moves (a rotation whose axis holds every vertex).
double default_fd_step(const Scene& scene, const ParameterSpec& param);

/// Finite-difference steps from a `--h` list: empty = default_fd_step per parameter, one value =
/// that value for all, else one per parameter. Throws qsil::Error on a count mismatch.
std::vector<double> fd_steps(const Scene& scene, const std::vector<ParameterSpec>& params,
                             const std::vector<double>& h);

}  // namespace qsil
