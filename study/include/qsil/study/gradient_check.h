#pragma once
/// @file gradient_check.h
/// Image-level gradient checks: `qsil grad` (interior + quadric boundary term) against central
/// finite differences with common random numbers, on small scenes. Used by
/// tests/integrators/gradient_vs_fd_test.cpp (CI sizes) and tools/tool_check_gradients.cpp
/// (`qsil-check_gradients`: the same statistics at higher resolution and spp); part of the
/// library so that the tool does not include test code.
///
/// Statistics of one comparison (derivative channels R, G, B of every pixel, "pixel-channels"):
/// - image sums (sum over pixels of the mean of R, G, B) of both estimators with their standard
///   errors (pixels are independent, so variances add); agreement: |sum_grad - sum_fd| within 3
///   combined standard errors (two-sided, 99.7% for Gaussian sums);
/// - the fraction of pixel-channels with |grad - fd| <= 4 combined standard errors (per pixel
///   SEs from the films; for Gaussian errors 99.994% of pixel-channels pass, the criterion asks
///   98%: the slack is for heavy-tailed pixels whose SE is itself noisy at CI spp);
/// - the interior term alone (--boundary none) for the same seed, to tell what the boundary term
///   adds, and the primary term's share is visible as the difference of the two.
/// Case files are relative to the repository root; resolve them with Case::resolved() (the test
/// passes the source tree, the tool its --root).

#include "qsil/integrators/estimator.h"
#include "qsil/parameters.h"
#include "qsil/scene.h"

#include <filesystem>
#include <map>
#include <string>
#include <vector>

namespace qsil::gradcheck {

/// One configuration {scene, parameter, FD step}, as in Mitsuba 3's test_ad_integrators.py.
struct Case {
  std::string name;
  std::string file;                             ///< relative to the repository root (or resolved)
  std::map<std::string, std::string> defaults;  ///< -D overrides except res/spp (set per run)
  std::string param;
  double h = 0;  ///< FD step (scene units of theta)
  /// A copy whose `file` is `root / file` (an absolute `file` stays as it is).
  Case resolved(const std::filesystem::path& root) const;
};

/// The gradient-check cases: four bundled scenes, two boundary-term scenes, a flat-shaded
/// (face_normals) case, three smooth-shading cases and three intersection-curve cases:
/// spot-mirror, shadow-quad, direct, sunk (scenes/), plane-light, spot-selfshadow, faceted-cube,
/// smooth-cube, mirror-point, open-box-point, sunk-sphere, wall-floor, two-spheres
/// (tests/data/gradient/).
std::vector<Case> cases();

/// The case named `name`; throws qsil::Error "no gradient case NAME" otherwise.
const Case& find_case(const std::string& name);

/// Loads a case's scene (its `file` as given: resolve it first) at res x res pixels and spp
/// samples per pixel. Throws qsil::Error from the scene loader.
Scene load_case(const Case& c, int res, int spp);

/// One pixel-channel that disagrees, for localisation.
struct Outlier {
  int x = 0, y = 0, channel = 0;  ///< pixel (0,0 top-left) and channel (0 R, 1 G, 2 B)
  double grad = 0, grad_se = 0, fd = 0, fd_se = 0, interior = 0;
  /// (grad - fd) / combined standard error.
  double z() const;
};

/// Statistics of one grad-vs-FD comparison (see the file comment).
struct Agreement {
  int res = 0, grad_spp = 0, fd_spp = 0;
  double h = 0;
  ImageSum grad, fd, interior;  ///< image sums (interior: --boundary none, same seed as grad)
  double sum_se = 0;            ///< combined standard error of the sums
  double pixel_fraction_within_4se = 0;
  int pixel_channels = 0, pixel_channels_outside = 0;
  /// The same fraction over the pixel-channels FD resolved (its estimate or its standard error is
  /// non-zero): where every FD sample pair saw the same path, 0 +- 0 is no oracle.
  double resolved_fraction_within_4se = 0;
  int resolved_pixel_channels = 0;
  /// Fraction of pixel-channels where FD is clearly non-zero (|fd| > 4 se): the test has signal.
  double fd_signal_fraction = 0;
  std::vector<Outlier> worst;  ///< the largest |z| first (up to 8)
  double grad_seconds = 0, fd_seconds = 0, interior_seconds = 0;
  uint64_t traversals = 0, zero_traversals = 0;  ///< boundary-term samples of grad, and the zero ones
  uint64_t nonfinite = 0;
  /// (sum_grad - sum_fd) / sum_se.
  double sum_z() const;
  /// |sum_grad - sum_fd| <= 3 sum_se.
  bool sums_agree() const;
  /// At least 98% of pixel-channels within 4 combined standard errors.
  bool pixels_agree() const;
};

/// Compares films of the same layout (one parameter): grad (and optionally the interior term)
/// against FD.
Agreement compare(const RenderResult& g, const RenderResult& f, const RenderResult* interior);

/// The rendered films of a comparison (kept for localisation: per-pixel dumps).
struct Films {
  RenderResult grad, fd, interior;
};

/// Renders grad (seed 21), FD (seed 22: independent of grad) and optionally the interior term
/// alone (seed 21) of a case (file resolved) at res x res, and compares them. `threads` 0 = all
/// cores; `keep` (may be null) receives the films.
Agreement run(const Case& c, int res, int grad_spp, int fd_spp, double h, bool with_interior, int threads = 0,
              Films* keep = nullptr);

/// Per-pixel-channel values as CSV (x,y,c,primal,grad,grad_se,fd,fd_se,interior) for
/// localisation. Throws qsil::Error naming the file when it cannot be written.
void write_csv(const std::string& path, const Films& films);

/// The statistics of a comparison as text lines (the same lines in the tests and the tool).
std::string describe(const std::string& name, const Agreement& a);

}  // namespace qsil::gradcheck
