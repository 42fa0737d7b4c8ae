#pragma once
/// @file gradient_scenes.h
/// The image-level gradient checks of issue "boundary term": `qsil grad` (interior + boundary
/// term) against central finite differences with common random numbers, on small scenes. Shared
/// by tests/integrators/gradient_vs_fd_test.cpp (CI sizes) and tools/tool_check_gradients.cpp
/// (`qsil-check_gradients`: the same statistics at higher resolution and spp).
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
/// Paths are relative to the repository root (tests run there, see tests/CMakeLists.txt).

#include "integrators/render.h"
#include "qsil/parameters.h"
#include "qsil/scene.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace qsil::gradcheck {

/// One configuration {scene, parameter, FD step}, as in Mitsuba 3's test_ad_integrators.py.
struct Case {
  std::string name;
  std::string file;                              ///< relative to the repository root
  std::map<std::string, std::string> defaults;   ///< -D overrides except res/spp (set per run)
  std::string param;
  double h = 0;                                  ///< FD step (scene units of theta)
};

/// The five scenes of the issue, in the order it lists them, and a flat-shaded (face_normals) case.
inline std::vector<Case> cases() {
  return {
      // Spot seen only in a GGX 0.01 mirror: secondary silhouettes at the mirror's vertices.
      {"spot-mirror", "scenes/spot-mirror.xml", {{"max_depth", "3"}}, "spot:translate:0,1,0", 1e-2},
      // The bunny's soft shadow on a static floor (plus its own primary silhouettes).
      {"shadow-quad", "scenes/shadow-quad.xml", {{"max_depth", "3"}}, "object:translate:1,0,0", 1e-2},
      // Spot seen directly in front of a backdrop: primary silhouettes.
      {"direct", "scenes/direct.xml", {{"max_depth", "3"}}, "spot:translate:1,0,0", 1e-2},
      // A floor moving toward a small area light: the light's outline is the whole derivative.
      {"plane-light", "tests/data/gradient/plane-light.xml", {}, "floor:translate:0,1,0", 1e-2},
      // Spot translating under a small light: shadows on itself, shading points on the moving shape.
      {"spot-selfshadow", "tests/data/gradient/spot-selfshadow.xml", {}, "spot:translate:1,0,0", 1e-2},
      // A flat-shaded cube rotating: its creases are discontinuities (primary and secondary).
      {"faceted-cube", "tests/data/gradient/faceted-cube.xml", {}, "cube:rotate:0,1,0", 1e-2},
  };
}

inline const Case& find_case(const std::string& name) {
  static const std::vector<Case> all = cases();
  for (const Case& c : all)
    if (c.name == name) return c;
  throw std::runtime_error("no gradient case " + name);
}

/// Loads a case's scene at a resolution and spp.
inline Scene load_case(const Case& c, int res, int spp) {
  auto defaults = c.defaults;
  defaults["res"] = std::to_string(res);
  defaults["spp"] = std::to_string(spp);
  return load_scene(c.file, defaults);
}

/// One pixel-channel that disagrees, for localisation.
struct Outlier {
  int x = 0, y = 0, channel = 0;
  double grad = 0, grad_se = 0, fd = 0, fd_se = 0, interior = 0;
  double z() const { return (grad - fd) / std::max(1e-300, std::hypot(grad_se, fd_se)); }
};

/// Statistics of one grad-vs-FD comparison (see the file comment).
struct Agreement {
  int res = 0, grad_spp = 0, fd_spp = 0;
  double h = 0;
  ImageSum grad, fd, interior;   ///< image sums (interior: --boundary none, same seed as grad)
  double sum_se = 0;             ///< combined standard error of the sums
  double pixel_fraction_within_4se = 0;
  int pixel_channels = 0, pixel_channels_outside = 0;
  /// The same fraction over the pixel-channels FD resolved (its estimate or its standard error is
  /// non-zero): where every FD sample pair saw the same path, 0 +- 0 is no oracle.
  double resolved_fraction_within_4se = 0;
  int resolved_pixel_channels = 0;
  /// Fraction of pixel-channels where FD is clearly non-zero (|fd| > 4 se): the test has signal.
  double fd_signal_fraction = 0;
  std::vector<Outlier> worst;    ///< the largest |z| first (up to 8)
  double grad_seconds = 0, fd_seconds = 0, interior_seconds = 0;
  GradientReport report;
  uint64_t nonfinite = 0;
  double sum_z() const { return (grad.sum - fd.sum) / std::max(1e-300, sum_se); }
  bool sums_agree() const { return std::abs(grad.sum - fd.sum) <= 3 * sum_se; }
  bool pixels_agree() const { return pixel_fraction_within_4se >= 0.98; }
};

/// Compares films of the same layout (one parameter): grad (and optionally the interior term)
/// against FD.
inline Agreement compare(const RenderResult& g, const RenderResult& f, const RenderResult* interior) {
  Agreement a;
  std::vector<Outlier> all;
  for (int y = 0; y < g.film.height(); ++y)
    for (int x = 0; x < g.film.width(); ++x)
      for (int c = 0; c < 3; ++c) {
        const int ch = 3 + c;
        Outlier o;
        o.x = x;
        o.y = y;
        o.channel = c;
        o.grad = g.film.mean(ch, x, y);
        o.grad_se = g.film.standard_error(ch, x, y);
        o.fd = f.film.mean(ch, x, y);
        o.fd_se = f.film.standard_error(ch, x, y);
        o.interior = interior ? interior->film.mean(ch, x, y) : 0.0;
        const double se = std::hypot(o.grad_se, o.fd_se);
        const bool within = std::abs(o.grad - o.fd) <= 4 * se + 1e-12;
        a.pixel_channels_outside += !within;
        ++a.pixel_channels;
        a.fd_signal_fraction += std::abs(o.fd) > 4 * o.fd_se;
        if (o.fd != 0 || o.fd_se > 0) {
          ++a.resolved_pixel_channels;
          a.resolved_fraction_within_4se += within;
        }
        all.push_back(o);
      }
  a.pixel_fraction_within_4se = 1.0 - double(a.pixel_channels_outside) / a.pixel_channels;
  a.resolved_fraction_within_4se =
      a.resolved_pixel_channels > 0 ? a.resolved_fraction_within_4se / a.resolved_pixel_channels : 1.0;
  a.fd_signal_fraction /= a.pixel_channels;
  std::sort(all.begin(), all.end(), [](const Outlier& p, const Outlier& q) { return std::abs(p.z()) > std::abs(q.z()); });
  all.resize(std::min<size_t>(all.size(), 8));
  a.worst = all;
  a.grad = derivative_image_sum(g.film, 1, 0);
  a.fd = derivative_image_sum(f.film, 1, 0);
  if (interior) a.interior = derivative_image_sum(interior->film, 1, 0);
  a.sum_se = std::hypot(a.grad.standard_error, a.fd.standard_error);
  a.nonfinite = g.nonfinite + f.nonfinite;
  return a;
}

/// The rendered films of a comparison (kept for localisation: per-pixel dumps).
struct Films {
  RenderResult grad, fd, interior;
};

/// Renders grad (seed 21), FD (seed 22: independent of grad) and optionally the interior term
/// alone (seed 21) of a case, and compares them.
inline Agreement run(const Case& c, int res, int grad_spp, int fd_spp, double h, bool with_interior,
                     int threads = 0, Films* keep = nullptr) {
  const Scene scene = load_case(c, res, grad_spp);
  const std::vector<ParameterSpec> params{parse_parameter(c.param, scene)};
  RenderOptions o;
  o.progress = false;
  o.threads = threads;
  o.seed = 21;
  o.spp = grad_spp;
  Agreement a;
  GradientReport report;
  const RenderResult g = render_gradient(scene, params, o, GradientOptions{BoundaryMethod::Quadric, 1}, &report);
  RenderResult interior;
  if (with_interior) interior = render_gradient(scene, params, o, GradientOptions{BoundaryMethod::None, 1});
  o.seed = 22;
  o.spp = fd_spp;
  const RenderResult f = render_finite_differences(scene, params, {h}, o);
  a = compare(g, f, with_interior ? &interior : nullptr);
  a.res = res;
  a.grad_spp = grad_spp;
  a.fd_spp = fd_spp;
  a.h = h;
  a.grad_seconds = g.seconds;
  a.fd_seconds = f.seconds;
  a.interior_seconds = with_interior ? interior.seconds : 0.0;
  a.report = report;
  if (keep) {
    keep->grad = g;
    keep->fd = f;
    keep->interior = interior;
  }
  return a;
}

/// Per-pixel-channel values as CSV (x,y,c,primal,grad,grad_se,fd,fd_se,interior) for localisation.
inline void write_csv(const std::string& path, const Films& films) {
  FILE* out = std::fopen(path.c_str(), "w");
  if (!out) throw std::runtime_error("cannot write " + path);
  std::fprintf(out, "x,y,c,primal,grad,grad_se,fd,fd_se,interior\n");
  const Film& g = films.grad.film;
  const bool has_interior = films.interior.film.width() == g.width();
  for (int y = 0; y < g.height(); ++y)
    for (int x = 0; x < g.width(); ++x)
      for (int c = 0; c < 3; ++c)
        std::fprintf(out, "%d,%d,%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", x, y, c, g.mean(c, x, y), g.mean(3 + c, x, y), g.standard_error(3 + c, x, y),
                     films.fd.film.mean(3 + c, x, y), films.fd.film.standard_error(3 + c, x, y),
                     has_interior ? films.interior.film.mean(3 + c, x, y) : 0.0);
  std::fclose(out);
}

/// Prints the statistics of a comparison (the same lines in the tests and the tool).
inline std::string describe(const std::string& name, const Agreement& a) {
  char buf[512];
  std::string s;
  std::snprintf(buf, sizeof buf,
                "%s: %dx%d, grad %d spp (%.1f s), fd %d spp h=%g (%.1f s)\n"
                "  image sum grad %.4g +- %.3g | fd %.4g +- %.3g | diff %.2f combined SE [%s]\n"
                "  pixel-channels within 4 SE: %.2f%% (%d of %d outside) [%s]\n",
                name.c_str(), a.res, a.res, a.grad_spp, a.grad_seconds, a.fd_spp, a.h, a.fd_seconds, a.grad.sum,
                a.grad.standard_error, a.fd.sum, a.fd.standard_error, a.sum_z(), a.sums_agree() ? "ok" : "FAIL",
                100 * a.pixel_fraction_within_4se, a.pixel_channels_outside, a.pixel_channels,
                a.pixels_agree() ? "ok" : "FAIL");
  s += buf;
  if (a.interior_seconds > 0) {
    std::snprintf(buf, sizeof buf, "  interior term alone (--boundary none): %.4g +- %.3g; boundary term adds %.4g\n",
                  a.interior.sum, a.interior.standard_error, a.grad.sum - a.interior.sum);
    s += buf;
  }
  std::snprintf(buf, sizeof buf, "  worst pixel-channels (x, y, c: grad +- se | fd +- se | interior | z):\n");
  s += buf;
  for (const Outlier& o : a.worst) {
    std::snprintf(buf, sizeof buf, "    (%d, %d, %c): %.4g +- %.3g | %.4g +- %.3g | %.4g | %+.1f\n", o.x, o.y, "RGB"[o.channel],
                  o.grad, o.grad_se, o.fd, o.fd_se, o.interior, o.z());
    s += buf;
  }
  return s;
}

}  // namespace qsil::gradcheck
