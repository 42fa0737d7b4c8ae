#pragma once
/// @file render.h
/// Whole-image estimators: the primal image (`qsil render`), the gradient image (primal +
/// interior term in forward mode + boundary term, `qsil grad`) and finite differences (`qsil fd`).

#include "qsil/film.h"
#include "qsil/parameters.h"
#include "qsil/scene.h"

#include <cstdint>
#include <string>
#include <vector>

namespace qsil {

/// Options shared by every estimator.
struct RenderOptions {
  int spp = -1;          ///< samples per pixel; -1 = the scene's sampler sample_count
  uint64_t seed = 0;     ///< PCG32 seed; results are bit-identical for any thread count
  int threads = 0;       ///< 0 = all cores
  bool progress = true;  ///< progress bar on stderr (runs > 1 s)
};

/// What a render produced and what it cost.
struct RenderResult {
  Film film{1, 1, 1};
  int spp = 0;
  double seconds = 0;          ///< wall time of the pixel loop (excludes loading)
  uint64_t rays = 0;           ///< ray queries issued
  uint64_t nonfinite = 0;      ///< samples with a NaN/inf value (replaced by 0 and reported)
};

/// Renders the primal image. Film channels: R, G, B.
RenderResult render_primal(const Scene& scene, const RenderOptions& options);

/// Channel names of a gradient film/EXR: R,G,B then dtheta<k>.R/G/B per parameter.
std::vector<std::string> gradient_channel_names(int num_params);

/// Gradient films hold 3(1+K) named channels followed by K hidden channels: per parameter, the
/// per-sample mean of its three derivative channels, so that the image sum of a derivative has
/// an exact standard error (channels are correlated within a sample).
int gradient_film_channels(int num_params);

/// Image sum over pixels of the mean of parameter k's R,G,B derivative, and its standard error
/// (pixels are independent: the variances add).
struct ImageSum {
  double sum = 0;
  double standard_error = 0;
};
ImageSum derivative_image_sum(const Film& film, int num_params, int k);

/// The boundary-term estimator of `qsil grad` (docs/architecture.md §7).
enum class BoundaryMethod {
  None,        ///< interior term only
  Quadric,     ///< edge forest with the dual box + bounding quadric pair test [QSS] (default)
  QuadricBox,  ///< edge forest with the dual box test only (ablation)
  VSphere,     ///< Li 2019's Hough-space tree with the hollow v-sphere test (edgetree/vsphere_sampler.h)
  VSphereSolid,///< the same with redner's original solid v-sphere test ([QSS] App. F)
  Uniform,     ///< no rejection, edges in proportion to length x dihedral angle (edgetree/uniform_sampler.h)
};
/// Parses "none" | "quadric" | "quadric-box" | "vsphere" | "vsphere-solid" | "uniform"; throws
/// qsil::Error naming the value otherwise.
BoundaryMethod parse_boundary_method(const std::string& name);

/// Options of the gradient estimator.
struct GradientOptions {
  BoundaryMethod boundary = BoundaryMethod::Quadric;
  int boundary_spp = 1;  ///< discontinuity samples per shading point
};

/// Cost report of a gradient render (in addition to RenderResult).
struct GradientReport {
  double forest_seconds = 0;      ///< edge-forest build
  double boundary_seconds = 0;    ///< wall time attributed to the boundary term (thread-time share)
  uint64_t traversals = 0;        ///< boundary-term samples drawn
  uint64_t zero_traversals = 0;   ///< ...that contributed nothing
};

/// Renders the primal image and its derivative with respect to each parameter (1 to 8) from the
/// same paths: interior term in forward mode plus the boundary term of `gopt.boundary`.
/// Film channels: gradient_film_channels(params.size()).
RenderResult render_gradient(const Scene& scene, const std::vector<ParameterSpec>& params, const RenderOptions& options,
                             const GradientOptions& gopt = {}, GradientReport* report = nullptr);

/// Default finite-difference step of a parameter: 1e-3 of the scene's bounding-box diagonal
/// divided by |direction| for translate and vertex (so the displacement is 1e-3 diagonal),
/// 1e-3 radians for rotate, 1e-3 (relative) for scale.
double default_fd_step(const Scene& scene, const ParameterSpec& param);

/// Central finite differences (I(theta+h) - I(theta-h)) / 2h per parameter with common random
/// numbers (both sides use identical sample streams), plus the primal at theta = 0, in the same
/// film layout as render_gradient. `steps` has one h per parameter.
RenderResult render_finite_differences(const Scene& scene, const std::vector<ParameterSpec>& params,
                                       const std::vector<double>& steps, const RenderOptions& options);

}  // namespace qsil
