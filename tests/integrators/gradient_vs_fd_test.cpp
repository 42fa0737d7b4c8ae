// Image-level correctness of `qsil grad` (interior + quadric boundary term) against central finite
// differences with common random numbers, on small images with fixed seeds. Criteria: the image
// sums agree within 3 combined standard errors (two-sided, 99.7% for a correct estimator) and at
// least 98% of pixel-channels lie within 4 combined standard errors (a correct estimator fails 0.006% of Gaussian
// pixel-channels; the slack is for heavy-tailed pixels whose SE is itself noisy). The scenes and the statistics are
// shared with `qsil-check_gradients` (tools/tool_check_gradients.cpp), which runs them at higher spp and resolution;
// its output is docs/gradient-checks.md. The whole file runs in a few seconds.
#include "qsil/study/gradient_check.h"
#include "qsil/scene.h"
#include "test_data.h"

#include <gtest/gtest.h>

namespace qsil {
namespace {

using gradcheck::Agreement;

/// Which criteria a case checks: both (image sum and per pixel), or the image sum alone.
enum class Pixels { Checked, SumOnly };

/// Runs a case and checks the criteria above, printing the statistics.
void expect_agreement(const std::string& name, int res, int grad_spp, int fd_spp, double h = 0,
                      Pixels pixels = Pixels::Checked) {
  const gradcheck::Case c = gradcheck::find_case(name).resolved(QSIL_SOURCE_DIR);
  const Agreement a = gradcheck::run(c, res, grad_spp, fd_spp, h > 0 ? h : c.h, /*with_interior=*/false);
  const std::string text = gradcheck::describe(name, a);
  std::printf("%s", text.c_str());
  EXPECT_NEAR(a.grad.sum, a.fd.sum, 3 * a.sum_se) << text;
  if (pixels == Pixels::Checked) { EXPECT_GE(a.pixel_fraction_within_4se, 0.98) << text; }
  // Not vacuous: the image sum, or at least 5% of the pixel-channels, clearly non-zero in FD.
  EXPECT_TRUE(std::abs(a.fd.sum) > 3 * a.fd.standard_error || a.fd_signal_fraction >= 0.05)
      << text << "the derivative must be clearly non-zero (signal fraction " << a.fd_signal_fraction << ")";
  EXPECT_EQ(a.nonfinite, 0u);
}

/// Sum of the per-sample mean derivative (film channel 3(1+K)+k, K = 1) over pixels whose centre and
/// four corners all see the floor y = 0 inside the box x0 < x < x1, |z| < zmax, with its standard
/// error, and the number of those pixels with the given sign.
struct RegionSum {
  double sum = 0, se = 0;
  int pixels = 0, positive = 0, negative = 0;
};
RegionSum floor_region_sum(const Scene& scene, const Film& film, double x0, double x1, double zmax) {
  const Camera& cam = scene.camera;
  const Vec3 o = cam.origin();
  auto inside = [&](double fx, double fy) {
    const Vec3 d = cam.direction(fx, fy);
    if (!(d.y() < 0)) return false;
    const Vec3 p = o + d * (-o.y() / d.y());
    return p.x() > x0 && p.x() < x1 && std::abs(p.z()) < zmax;
  };
  RegionSum r;
  double var = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      if (!(inside(x + 0.5, y + 0.5) && inside(x, y) && inside(x + 1, y) && inside(x, y + 1) && inside(x + 1, y + 1)))
        continue;
      const double m = film.mean(6, x, y), se = film.standard_error(6, x, y);
      r.sum += m;
      var += se * se;
      ++r.pixels;
      r.positive += m > 0;
      r.negative += m < 0;
    }
  r.se = std::sqrt(var);
  return r;
}

}  // namespace

// ---- Agreement with finite differences (see the file comment for the criteria).

// A floor moving toward a small area light: the interior term is exactly zero (fixed directions,
// constant emission), so the whole derivative is the light's outline moving relative to the
// moving shading points (secondary boundary term at a moving p, static edges).
// At 256 spp the image sum's SE is ~3% of the sum; about 3 s on 2 cores.
TEST(GradientVsFD, FloorMovingTowardASmallAreaLight) { expect_agreement("plane-light", 32, 256, 1024); }

// Primary silhouettes: Spot seen directly in front of a backdrop, moving sideways. 16x16 at
// 2048 spp (grad) / 4096 spp (FD): ~12 s alone, 31-33 s under `ctest -j2` on 2 cores, hence the
// ctest label "slow" (suite prefix Slow, tests/CMakeLists.txt).
TEST(SlowGradientVsFD, DirectPrimarySilhouettes) { expect_agreement("direct", 16, 2048, 4096); }

// A moving object that shadows itself under a small area light: shading points on the moving
// shape, whose own silhouettes and the light's outline move relative to them.
TEST(GradientVsFD, MovingObjectShadowsItself) { expect_agreement("spot-selfshadow", 16, 2048, 4096); }

// A flat-shaded cube rotating (face_normals): every crease is a discontinuity of the shading,
// seen by the camera and by the backdrop's shading points. Image sum only: at the backdrop
// pixels beside the cube the cube's silhouette changes a path in ~5 of 4096 FD sample pairs,
// so FD's per-pixel standard error is unreliable there (0 +- 0 against grad 0.044 +- 0.004), and
// a larger h smears the silhouettes across pixels. Per-pixel: 97.0% within 4 SE (FD 2048 spp,
// h 0.01), qsil-check_gradients --case faceted-cube.
TEST(GradientVsFD, FlatShadedCubeCreases) { expect_agreement("faceted-cube", 16, 1024, 2048, 0, Pixels::SumOnly); }

// Reflection only: Spot is outside the view and seen in a GGX alpha 0.01 mirror. Image sum only
// at CI size: some mirror pixels see Spot only through the lobe's tail, where almost no FD
// sample pair changes path (FD 0 +- 0 or one sample, while the gradient is ~1e-4 +- 1e-5), so
// FD is no per-pixel oracle there at 4096 spp; qsil-check_gradients reports the per-pixel
// statistics (docs/gradient-checks.md). Before the shading-normal adaptation this failed at
// -50.5 +- 2.5 (grad) vs -24.4 +- 1.2 (FD), 32x32.
TEST(GradientVsFD, SpotMirrorReflectionOnly) { expect_agreement("spot-mirror", 16, 2048, 4096, 0, Pixels::SumOnly); }

// A penumbra on a static floor (static shading points; the bunny's edges move). Image sum only,
// for the same reason: far floor pixels see penumbrae FD does not resolve at this spp.
TEST(GradientVsFD, ShadowQuadPenumbraOnAStaticFloor) {
  expect_agreement("shadow-quad", 16, 2048, 4096, 0, Pixels::SumOnly);
}

// A sphere occluder between a floor and a small sphere light: a mesh emitter, which the
// light-aware importance knows by its bounding sphere (edgetree::LightSphere). The floor is static
// and max_depth = 2, so the whole derivative is the boundary term. At 4096 / 16384 spp the image
// sum's combined SE is ~4 % of the sum; about 17 s on 2 cores.
TEST(GradientVsFD, SphereOccluderUnderASphereLight) { expect_agreement("sphere-light", 32, 4096, 16384); }

// ---- Sign test.

// penumbra-sign.xml: a square occluder between a square light and the floor, all axis-aligned.
// Translating the occluder along +x moves its shadow along +x: the penumbra on the +x side
// (0.35 < x < 0.85 on the floor, see the scene file) darkens and the one on the -x side brightens.
// The floor is static and max_depth = 2, so the interior term is zero there and the sign comes
// from the boundary term alone. Each region's image sum must have the expected sign by more than
// 5 standard errors (a sign error flips both), and at least 90% of its pixels must agree.
TEST(GradientSign, OccluderMovedTowardTheLightsSideDarkensThePenumbraOnThatSide) {
  const Scene scene =
      load_scene(test::data_file("tests/data/gradient/penumbra-sign.xml"), {{"res", "32"}, {"spp", "64"}});
  const std::vector<ParameterSpec> params{parse_parameter("occluder:translate:1,0,0", scene)};
  RenderOptions o;
  o.progress = false;
  o.seed = 31;
  const RenderResult g = Estimator(scene, EstimatorConfig::gradient(params)).run(o);
  const RenderResult interior = Estimator(scene, EstimatorConfig::gradient(params, Method::None)).run(o);
  // Inner parts of the penumbrae (a margin of 0.05 inside 0.35 .. 0.85), well inside |z| < 0.35.
  const RegionSum plus = floor_region_sum(scene, g.film, 0.40, 0.80, 0.30);
  const RegionSum minus = floor_region_sum(scene, g.film, -0.80, -0.40, 0.30);
  const RegionSum plus_interior = floor_region_sum(scene, interior.film, 0.40, 0.80, 0.30);
  std::printf(
      "+x penumbra: %d pixels, sum %.4g +- %.3g (%d negative); -x penumbra: %d pixels, sum %.4g +- %.3g (%d "
      "positive)\n",
      plus.pixels, plus.sum, plus.se, plus.negative, minus.pixels, minus.sum, minus.se, minus.positive);
  ASSERT_GE(plus.pixels, 10);
  ASSERT_GE(minus.pixels, 10);
  EXPECT_LT(plus.sum, -5 * plus.se) << "the +x penumbra must darken";
  EXPECT_GT(minus.sum, 5 * minus.se) << "the -x penumbra must brighten";
  EXPECT_GE(plus.negative, 0.9 * plus.pixels);
  EXPECT_GE(minus.positive, 0.9 * minus.pixels);
  EXPECT_EQ(plus_interior.sum, 0.0) << "the interior term has no part in a static floor's penumbra";
  // Finite differences agree in sign (the reference).
  o.seed = 32;
  const RenderResult f = Estimator(scene, EstimatorConfig::finite_differences(params, {1e-2})).run(o);
  EXPECT_LT(floor_region_sum(scene, f.film, 0.40, 0.80, 0.30).sum, 0.0);
  EXPECT_GT(floor_region_sum(scene, f.film, -0.80, -0.40, 0.30).sum, 0.0);
}

}  // namespace qsil
