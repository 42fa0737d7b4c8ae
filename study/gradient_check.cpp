/// @file gradient_check.cpp
/// Image-level gradient checks against finite differences; see gradient_check.h.

#include "qsil/study/gradient_check.h"

#include "qsil/error.h"
#include "qsil/files.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace qsil::gradcheck {

Case Case::resolved(const std::filesystem::path& root) const {
  Case c = *this;
  if (std::filesystem::path(file).is_relative()) c.file = (root / file).string();
  return c;
}

std::vector<Case> cases() {
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
      // A coarse smooth-shaded cube (vertex normals up to 55 deg off the faces') moving toward the
      // camera: the shading must not jump at its edges (smooth shading).
      {"smooth-cube", "tests/data/gradient/smooth-cube.xml", {}, "cube:translate:0,0,1", 1e-2},
      // One mirror point of spot-mirror whose GGX lobe sees Spot's silhouette (a 1x1 image with a
      // 0.02 deg field of view): the boundary term through a near-specular lobe. FD needs a small
      // step: the radiance varies on the scale of the lobe's footprint on Spot (h = 0.01 is 8 %
      // off at alpha 0.01, h = 0.003 and 0.001 agree).
      {"mirror-point", "tests/data/gradient/mirror-point.xml", {}, "spot:translate:0,1,0", 2e-3},
      // One point of the smooth-shaded, twosided open box's right wall near the back corner (a
      // 1x1 image with a 0.02 deg field of view), depth 2: edges in the point's own plane that do
      // not bound its triangle (face_in_plane, boundary_term.h).
      {"open-box-point", "tests/data/gradient/open-box-point.xml", {}, "box:rotate:0,1,0", 1.2e-2},
      // Spot sunk into the ground to its belly, rising: the curve where it pierces the floor
      // (intersection curves), primary and secondary.
      {"sunk", "scenes/sunk.xml", {}, "spot:translate:0,1,0", 1e-2},
      // A sphere sunk into a floor, moved up, and a wall piercing a floor under an area light, moved
      // along its normal (intersection curves: tests/integrators/intersection_curves_test.cpp).
      {"sunk-sphere", "tests/data/gradient/sunk-sphere.xml", {}, "sphere:translate:0,1,0", 1e-2},
      {"wall-floor", "tests/data/gradient/wall-floor.xml", {}, "wall:translate:0,0,1", 1e-2},
      // One OBJ of two overlapping spheres (a self-intersecting mesh) under an area light, translated.
      {"two-spheres", "tests/data/gradient/two-spheres.xml", {}, "spheres:translate:1,0,0", 1e-2},
      // A sphere occluder between a floor and a small sphere light (a mesh emitter; Mitsuba 3's
      // TranslateOccluderAreaLight configuration), translated: the light-aware importance of a
      // light that is not a quad (edgetree::LightSphere).
      {"sphere-light", "scenes/stability/sphere-light.xml", {}, "occluder:translate:1,0,0", 1e-2},
      // The wing nut on a rough-metal floor under a small sphere light, translated: glossy vertices
      // and a mesh emitter.
      {"glossy-sphere-light", "scenes/stability/glossy-sphere-light.xml", {}, "wingnut:translate:1,0,0", 1e-2},
  };
}

const Case& find_case(const std::string& name) {
  static const std::vector<Case> all = cases();
  for (const Case& c : all)
    if (c.name == name) return c;
  throw Error("no gradient case " + name);
}

Scene load_case(const Case& c, int res, int spp) {
  auto defaults = c.defaults;
  defaults["res"] = std::to_string(res);
  defaults["spp"] = std::to_string(spp);
  return load_scene(c.file, defaults);
}

double Outlier::z() const { return (grad - fd) / std::max(1e-300, std::hypot(grad_se, fd_se)); }

double Agreement::sum_z() const { return (grad.sum - fd.sum) / std::max(1e-300, sum_se); }
bool Agreement::sums_agree() const { return std::abs(grad.sum - fd.sum) <= 3 * sum_se; }
bool Agreement::pixels_agree() const { return pixel_fraction_within_4se >= 0.98; }

Agreement compare(const RenderResult& g, const RenderResult& f, const RenderResult* interior) {
  Agreement a;
  std::vector<Outlier> all;
  for (int y = 0; y < g.film.height(); ++y)
    for (int x = 0; x < g.film.width(); ++x)
      for (int c = 0; c < 3; ++c) {
        const int ch = g.film.layout().derivative(0, c);
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
  std::sort(all.begin(), all.end(),
            [](const Outlier& p, const Outlier& q) { return std::abs(p.z()) > std::abs(q.z()); });
  all.resize(std::min<size_t>(all.size(), 8));
  a.worst = all;
  a.grad = g.film.derivative_sum(0);
  a.fd = f.film.derivative_sum(0);
  if (interior) a.interior = interior->film.derivative_sum(0);
  a.sum_se = std::hypot(a.grad.standard_error, a.fd.standard_error);
  a.nonfinite = g.nonfinite + f.nonfinite;
  return a;
}

Agreement run(const Case& c, int res, int grad_spp, int fd_spp, double h, bool with_interior, int threads,
              Films* keep) {
  const Scene scene = load_case(c, res, grad_spp);
  const std::vector<ParameterSpec> params{parse_parameter(c.param, scene)};
  RenderOptions o;
  o.progress = false;
  o.threads = threads;
  o.seed = 21;
  o.spp = grad_spp;
  const RenderResult g = Estimator(scene, EstimatorConfig::gradient(params, Method::Quadric)).run(o);
  RenderResult interior;
  if (with_interior) interior = Estimator(scene, EstimatorConfig::gradient(params, Method::None)).run(o);
  o.seed = 22;
  o.spp = fd_spp;
  const RenderResult f = Estimator(scene, EstimatorConfig::finite_differences(params, {h})).run(o);
  Agreement a;
  a = compare(g, f, with_interior ? &interior : nullptr);
  a.res = res;
  a.grad_spp = grad_spp;
  a.fd_spp = fd_spp;
  a.h = h;
  a.grad_seconds = g.seconds;
  a.fd_seconds = f.seconds;
  a.interior_seconds = with_interior ? interior.seconds : 0.0;
  a.traversals = g.traversals;
  a.zero_traversals = g.zero_traversals;
  if (keep) {
    keep->grad = g;
    keep->fd = f;
    keep->interior = interior;
  }
  return a;
}

void write_csv(const std::string& path, const Films& films) {
  std::string out = "x,y,c,primal,grad,grad_se,fd,fd_se,interior\n";
  const Film& g = films.grad.film;
  const FilmLayout& layout = g.layout();
  const bool has_interior = films.interior.film.layout().num_params() > 0;
  char line[256];
  for (int y = 0; y < g.height(); ++y)
    for (int x = 0; x < g.width(); ++x)
      for (int c = 0; c < 3; ++c) {
        const int d = layout.derivative(0, c);
        std::snprintf(line, sizeof line, "%d,%d,%d,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", x, y, c,
                      g.mean(layout.primal(c), x, y), g.mean(d, x, y), g.standard_error(d, x, y),
                      films.fd.film.mean(d, x, y), films.fd.film.standard_error(d, x, y),
                      has_interior ? films.interior.film.mean(d, x, y) : 0.0);
        out += line;
      }
  write_file(path, out);
}

std::string describe(const std::string& name, const Agreement& a) {
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
    std::snprintf(buf, sizeof buf, "    (%d, %d, %c): %.4g +- %.3g | %.4g +- %.3g | %.4g | %+.1f\n", o.x, o.y,
                  "RGB"[o.channel], o.grad, o.grad_se, o.fd, o.fd_se, o.interior, o.z());
    s += buf;
  }
  return s;
}

}  // namespace qsil::gradcheck
