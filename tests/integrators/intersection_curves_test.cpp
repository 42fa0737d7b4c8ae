// The boundary term at intersection curves (qsil/edgetree/intersection_curves.h,
// qsil/integrators/crossing_jump.h), image by image against central finite differences with
// common random numbers: surfaces that pierce each other, moved so that the curve where they
// meet moves.
//
// Statistic: S = sum over pixels of w(x) dI(x)/dtheta, the per-sample mean of the R, G, B
// derivatives (the film's hidden mean channel), with weights fixed before the runs:
// - Signed: w = the sign of an independent pilot FD image (its own seed), so that the pixels'
//   contributions add instead of cancelling, as in reverse_test.cpp;
// - NearCurve: the same sign on the pixels within one pixel of the curves' image (every crossing
//   segment projected, hidden parts included), 0 elsewhere: where the curve is seen directly but
//   its share of the whole image is small;
// - Uniform: w = 1 (the image sum): where it is seen only through a glossy reflection.
// Pixels are independent, so the variance of S is sum w^2 se^2. For each case:
// - power: the combined standard error of grad and FD is at most 3 % of |S_fd|;
// - agreement: |S_grad - S_fd| <= 3 combined standard errors (two-sided, 99.7 % for a correct
//   estimator);
// - the test can fail: the same grad with the intersection curves switched off
//   (EstimatorConfig::intersection_curves, same seed) is more than 5 combined standard errors
//   from FD (the bias these curves remove).
// A scene without crossings renders the same film, bit for bit, with the curves on and off.
#include "qsil/edgetree/intersection_curves.h"
#include "qsil/integrators/estimator.h"
#include "qsil/integrators/reverse.h"
#include "qsil/scene.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

namespace qsil {
namespace {

/// S = sum_x w(x) dI(x)/dtheta_0 with its standard error (see the file comment).
ImageSum weighted_sum(const Film& film, const FilmLayout& layout, const std::vector<double>& w) {
  ImageSum s;
  double var = 0;
  const int c = layout.derivative_mean(0);
  for (int y = 0; y < film.height(); ++y)
    for (int x = 0; x < film.width(); ++x) {
      const double wx = w[size_t(y) * size_t(film.width()) + size_t(x)];
      s.sum += wx * film.mean(c, x, y);
      var += wx * wx * film.standard_error(c, x, y) * film.standard_error(c, x, y);
    }
  s.standard_error = std::sqrt(var);
  return s;
}

enum class Weights { Signed, NearCurve, Uniform };

/// 1 on the pixels within one pixel of the image of an intersection curve of `scene` (each
/// crossing segment sampled every quarter pixel of its projection), else 0.
std::vector<double> near_curves(const Scene& scene) {
  std::vector<edgetree::CurveMesh> meshes;
  for (size_t s = 0; s < scene.shapes.size(); ++s) meshes.push_back({&scene.shapes[s].mesh, int(s)});
  const Camera& cam = scene.camera;
  std::vector<double> mask(size_t(cam.width) * size_t(cam.height), 0.0);
  for (const edgetree::CrossingSegment& c : edgetree::find_intersection_curves(meshes)) {
    double z0 = 0, z1 = 0;
    const double len = (cam.project(c.p1, &z1) - cam.project(c.p0, &z0)).norm();
    const int n = int(std::ceil(4 * len)) + 1;
    for (int i = 0; i <= n; ++i) {
      double z = 0;
      const Vec2 f = cam.project(c.p0 + (double(i) / n) * (c.p1 - c.p0), &z);
      if (!(z > 0)) continue;
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int x = int(std::floor(f.x())) + dx, y = int(std::floor(f.y())) + dy;
          if (x >= 0 && y >= 0 && x < cam.width && y < cam.height) mask[size_t(y) * size_t(cam.width) + size_t(x)] = 1;
        }
    }
  }
  return mask;
}

struct CurveCase {
  std::string file;
  std::map<std::string, std::string> defines;
  std::string param;
  int grad_spp = 1024;
  double sppi = 0;  ///< 0: the method's default
  int fd_spp = 8192;
  double h = 0;  ///< FD step (0: default_fd_step)
  Weights weights = Weights::Signed;
  int off_spp = 0;  ///< spp of the run without the curves (0: grad_spp)
};

RenderOptions options(uint64_t seed, int spp) {
  RenderOptions o;
  o.seed = seed;
  o.spp = spp;
  o.progress = false;
  return o;
}

void expect_curves_agree(const CurveCase& c) {
  const Scene scene = load_scene(test::data_file(c.file), c.defines);
  const std::vector<ParameterSpec> params = parse_parameters({c.param}, scene);
  const std::vector<double> steps = c.h > 0 ? std::vector<double>{c.h} : std::vector<double>{};
  const Estimator fd(scene, EstimatorConfig::finite_differences(params, steps));
  // The weights (see the file comment), independent of everything below.
  std::vector<double> w(size_t(scene.camera.width) * size_t(scene.camera.height), 1.0);
  if (c.weights != Weights::Uniform) {
    const RenderResult pilot = fd.run(options(99, c.fd_spp / 4));
    const std::vector<double> mask = c.weights == Weights::NearCurve ? near_curves(scene) : w;
    for (int y = 0; y < scene.camera.height; ++y)
      for (int x = 0; x < scene.camera.width; ++x) {
        const size_t i = size_t(y) * size_t(scene.camera.width) + size_t(x);
        const double d = pilot.film.mean(fd.layout().derivative_mean(0), x, y);
        w[i] = mask[i] * (d > 0 ? 1.0 : (d < 0 ? -1.0 : 0.0));
      }
  }
  const ImageSum f = weighted_sum(fd.run(options(22, c.fd_spp)).film, fd.layout(), w);
  EstimatorConfig on = EstimatorConfig::gradient(params, Method::Quadric, c.sppi);
  EstimatorConfig off = on;
  off.intersection_curves = false;
  const Estimator grad_on(scene, on), grad_off(scene, off);
  const RenderResult r_on = grad_on.run(options(21, c.grad_spp));
  const ImageSum g = weighted_sum(r_on.film, grad_on.layout(), w);
  const ImageSum g_off =
      weighted_sum(grad_off.run(options(21, c.off_spp > 0 ? c.off_spp : c.grad_spp)).film, grad_off.layout(), w);
  const double se = std::hypot(g.standard_error, f.standard_error);
  const double se_off = std::hypot(g_off.standard_error, f.standard_error);
  std::printf("%s %s: grad %.5g +- %.3g, FD %.5g +- %.3g (z %.2f); without the curves %.5g +- %.3g (z %.2f); %s\n",
              c.file.c_str(), c.param.c_str(), g.sum, g.standard_error, f.sum, f.standard_error, (g.sum - f.sum) / se,
              g_off.sum, g_off.standard_error, (g_off.sum - f.sum) / se_off, grad_on.setup().describe().c_str());
  EXPECT_GT(grad_on.setup().crossing_segments, 0);
  EXPECT_LE(se, 0.03 * std::abs(f.sum)) << "no power";
  EXPECT_NEAR(g.sum, f.sum, 3 * se);
  EXPECT_GT(std::abs(g_off.sum - f.sum), 5 * se_off) << "the curves make no difference here: this case cannot fail";
  EXPECT_EQ(r_on.nonfinite, 0u);
}

// A sphere sunk 0.4 into a floor, under a constant environment, moved up: the circle where it
// meets the floor shrinks (seen directly, primary and secondary terms).
TEST(IntersectionCurvesVsFD, SphereSunkIntoAFloorMovedVertically) {
  expect_curves_agree(
      {"tests/data/gradient/sunk-sphere.xml", {{"res", "32"}}, "sphere:translate:0,1,0", 1024, 0, 8192});
}

// The same sphere moved sideways, seen from the side: the circle slides across the floor.
TEST(IntersectionCurvesVsFD, SphereSunkIntoAFloorMovedSideways) {
  expect_curves_agree({"tests/data/gradient/sunk-sphere.xml",
                       {{"res", "32"}, {"camx", "1.5"}},
                       "sphere:translate:1,0,0",
                       1024,
                       0,
                       8192});
}

// A sphere sunk 0.7 into a floor, moved up, seen only in a GGX alpha 0.05 mirror that stands in
// the floor itself: the circle seen from the mirror's (static) points, and the mirror's own
// crossing with the floor, static but moving relative to points of the moving sphere. The image
// sum (the curve is seen only through the blur of the lobe). About 50 s on 2 cores: suite Slow*.
TEST(SlowIntersectionCurvesVsFD, SphereSunkIntoAFloorSeenInAGlossyMirror) {
  expect_curves_agree({"tests/data/gradient/sunk-sphere-mirror.xml",
                       {{"res", "32"}},
                       "sphere:translate:0,1,0",
                       4096,
                       0,
                       16384,
                       0,
                       Weights::Uniform,
                       1024});
}

// A wall piercing a floor under a small area light, moved along its normal: the segment where
// they meet bounds the wall's shadow on the floor (secondary term at static floor points).
TEST(IntersectionCurvesVsFD, WallPiercingAFloorUnderAnAreaLight) {
  expect_curves_agree(
      {"tests/data/gradient/wall-floor.xml", {{"res", "32"}}, "wall:translate:0,0,1", 1024, 0, 8192, 0.01});
}

// One OBJ holding two overlapping spheres (a self-intersecting mesh) under a small area light,
// translated: the circle where its parts cross moves with it. The pixels near the circle's image
// (elsewhere the spheres' own shading and silhouettes dominate), two traversals per vertex:
// the crease between the parts is where the boundary term is noisiest. About 60 s: suite Slow*.
TEST(SlowIntersectionCurvesVsFD, SelfIntersectingMesh) {
  expect_curves_agree({"tests/data/gradient/two-spheres.xml",
                       {{"res", "32"}},
                       "spheres:translate:1,0,0",
                       2048,
                       2,
                       8192,
                       0,
                       Weights::NearCurve});
}

// ---- Reverse mode: the adjoint of an end's velocity reaches the five vertices that move it.

/// Mean and standard error over `runs` seeds of one(seed).
template <class F>
ImageSum over_seeds(int runs, F&& one) {
  std::vector<double> v;
  for (int i = 0; i < runs; ++i) v.push_back(one(uint64_t(500 + 13 * i)));
  ImageSum s;
  for (double x : v) s.sum += x / runs;
  double var = 0;
  for (double x : v) var += (x - s.sum) * (x - s.sum);
  s.standard_error = std::sqrt(var / (runs - 1) / runs);
  return s;
}

/// Forward mode, reverse mode (dL/dx of `shape_id`'s vertices dotted with the parameter's
/// velocities) and FD estimate the same S = sum w dI/dtheta (w: the sign of a pilot FD image):
/// reverse within 3.5 combined standard errors of each (each combined standard error at most 4 %
/// of the value), and reverse mode without the curves more than 5 away from FD.
void expect_reverse_agrees(const Scene& scene, const std::string& param, const std::string& shape_id, int runs) {
  const std::vector<ParameterSpec> params = parse_parameters({param}, scene);
  const std::vector<int> shapes = resolve_shapes(scene, {shape_id});
  const SceneVelocities vel = compute_velocities(scene, params);
  const int W = scene.camera.width, H = scene.camera.height, spp = scene.camera.spp;
  const Estimator fd(scene, EstimatorConfig::finite_differences(params, {1e-2}));
  const Film pilot = fd.run(options(99, 4 * spp)).film;
  std::vector<double> w(size_t(W) * H * 3), w_pixel(size_t(W) * H);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const double d = pilot.mean(fd.layout().derivative_mean(0), x, y);
      const double s = d > 0 ? 1.0 : (d < 0 ? -1.0 : 0.0);
      w_pixel[size_t(y) * W + x] = s;
      for (int c = 0; c < 3; ++c) w[3 * (size_t(y) * W + x) + c] = s / 3;  // the mean of R, G, B
    }
  const Estimator forward(scene, EstimatorConfig::gradient(params));
  ReverseConfig rc{shapes, Method::Quadric, 0};
  const ReverseEstimator reverse(scene, rc);
  rc.intersection_curves = false;
  const ReverseEstimator reverse_off(scene, rc);
  auto reverse_dot = [&](const ReverseResult& r) {
    double s = 0;
    for (size_t v = 0; v < r.gradient[0].size(); ++v)
      s += r.gradient[0][v].dot(vel.position[size_t(shapes[0])][v].col(0));
    return s;
  };
  const ImageSum a = over_seeds(runs, [&](uint64_t seed) {
    return weighted_sum(forward.run(options(seed + 1, spp)).film, forward.layout(), w_pixel).sum;
  });
  const ImageSum b = over_seeds(runs, [&](uint64_t seed) { return reverse_dot(reverse.run(w, options(seed, spp))); });
  const ImageSum b_off =
      over_seeds(runs, [&](uint64_t seed) { return reverse_dot(reverse_off.run(w, options(seed, spp))); });
  const ImageSum f = over_seeds(runs, [&](uint64_t seed) {
    return weighted_sum(fd.run(options(seed + 2, 4 * spp)).film, fd.layout(), w_pixel).sum;
  });
  const double se = std::hypot(a.standard_error, b.standard_error),
               se_fd = std::hypot(f.standard_error, b.standard_error);
  const double se_off = std::hypot(f.standard_error, b_off.standard_error);
  std::printf(
      "%s (%s's vertices): forward %.5g +- %.3g, reverse %.5g +- %.3g (z %.2f), FD %.5g +- %.3g (z %.2f); "
      "reverse without the curves %.5g +- %.3g (z %.2f)\n",
      param.c_str(), shape_id.c_str(), a.sum, a.standard_error, b.sum, b.standard_error, (b.sum - a.sum) / se, f.sum,
      f.standard_error, (b.sum - f.sum) / se_fd, b_off.sum, b_off.standard_error, (b_off.sum - f.sum) / se_off);
  EXPECT_LE(se, 0.04 * std::abs(a.sum)) << "no power";
  EXPECT_NEAR(b.sum, a.sum, 3.5 * se);
  EXPECT_LE(se_fd, 0.04 * std::abs(f.sum)) << "no power";
  EXPECT_NEAR(b.sum, f.sum, 3.5 * se_fd);
  EXPECT_GT(std::abs(b_off.sum - f.sum), 5 * se_off) << "the curves make no difference here: this case cannot fail";
}

// The sunk sphere moved sideways (seen from the side), differentiated with respect to the
// sphere's vertices (the ends' edge vertices), and the floor moved up with respect to the floor's
// (the ends' plane vertices).
TEST(IntersectionCurves, ReverseModeAgreesWithForwardModeAndFD) {
  const Scene scene = load_scene(test::data_file("tests/data/gradient/sunk-sphere.xml"),
                                 {{"res", "16"}, {"spp", "256"}, {"camx", "1.5"}});
  expect_reverse_agrees(scene, "sphere:translate:1,0,0", "sphere", 8);
  expect_reverse_agrees(scene, "floor:translate:0,1,0", "floor", 8);
}

// Where nothing crosses, the curves change nothing: the same film, bit for bit (the wall moved
// beside the floor; and the sphere lifted clear of it).
TEST(IntersectionCurves, SceneWithoutCrossingsIsUnchanged) {
  struct Case {
    std::string file;
    std::map<std::string, std::string> defines;
    std::string param;
  };
  for (const Case& c : {Case{"tests/data/gradient/wall-floor.xml", {{"wallx", "2.2"}}, "wall:translate:0,0,1"},
                        Case{"tests/data/gradient/sunk-sphere.xml", {{"height", "0.6"}}, "sphere:translate:0,1,0"}}) {
    std::map<std::string, std::string> defines = c.defines;
    defines["res"] = "16";
    const Scene scene = load_scene(test::data_file(c.file), defines);
    const std::vector<ParameterSpec> params = parse_parameters({c.param}, scene);
    EstimatorConfig on = EstimatorConfig::gradient(params), off = on;
    off.intersection_curves = false;
    const Estimator a(scene, on), b(scene, off);
    EXPECT_EQ(a.setup().crossing_segments, 0) << c.file;
    const Film fa = a.run(options(5, 16)).film, fb = b.run(options(5, 16)).film;
    int differ = 0;
    for (int ch = 0; ch < fa.layout().channels(); ++ch)
      for (int y = 0; y < fa.height(); ++y)
        for (int x = 0; x < fa.width(); ++x) differ += fa.mean(ch, x, y) != fb.mean(ch, x, y);
    EXPECT_EQ(differ, 0) << c.file;
    EXPECT_NE(fa.derivative_sum(0).sum, 0.0) << c.file;
  }
}

}  // namespace
}  // namespace qsil
