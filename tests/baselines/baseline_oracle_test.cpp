/// @file baseline_oracle_test.cpp
/// Unbiasedness of every --boundary estimator against the analytic oracle of
/// tests/integrators/boundary_oracle.h: a diffuse
/// receiver point p under a uniform square area light, partly blocked by a black CLOSED BOX (so
/// that the trees hold convex edges, some of them silhouettes from the Hough origin = the camera
/// centre and some not, besides the always-candidate outlines of the light and the floor):
///   L_o = rho L (F(light) - F(light ∩ shadow)),
/// F the exact Lambert form factor, the shadow the convex hull of the box's eight corners
/// projected from p onto the light's plane. Its derivative is the central difference of this
/// deterministic formula. The interior term is zero (black occluder, constant emission, fixed
/// receiver normal), so the boundary estimator alone must match within 3.5 standard errors
/// (two-sided, ~99.95% per case for a correct estimator; 8 cases), fixed seeds.

#include "integrators/boundary_oracle.h"

#include <gtest/gtest.h>

namespace qsil {
namespace {

using namespace oracle;

/// The black closed box of this oracle (z in [0.9, 1.1]).
Shape occluder_box() { return closed_box("occluder", Vec3(0.0, -0.2, 0.9), Vec3(0.6, 0.3, 1.1), 1); }

const Method kMethods[] = {Method::Quadric, Method::VSphere, Method::VSphereSolid, Method::Uniform};
const char* kNames[] = {"quadric", "vsphere", "vsphere-solid", "uniform"};

}  // namespace

// The box moves (+x), the receiver point is static: only the box's edges move.
TEST(BaselineOracle, MovingBoxMatchesLambertsFormulaDerivative) {
  const Shape box = occluder_box();
  const Scene scene = oracle_scene(box);
  const Vec3 p(0.05, 0.02, 0);
  const double h = 1e-5;
  const double exact = (radiance(box, p, h) - radiance(box, p, -h)) / (2 * h);
  ASSERT_GT(std::abs(exact), 0.05);
  for (int m = 0; m < 4; ++m) {
    const Estimate e = boundary_estimate(scene, kMethods[m], "occluder:translate:1,0,0", p, Vec3::Zero(), 1000000);
    std::printf("[moving box] %-14s exact %.5f estimate %.5f +- %.5f\n", kNames[m], exact, e.mean, e.se);
    EXPECT_NEAR(e.mean, exact, 3.5 * e.se) << kNames[m];
    EXPECT_LT(e.se, 0.1 * std::abs(exact)) << kNames[m];
  }
}

// The receiver point moves (+x): the static box's and the light's outlines move relative to it.
TEST(BaselineOracle, MovingReceiverSeesStaticBoxAndLightOutlinesMove) {
  const Shape box = occluder_box();
  const Scene scene = oracle_scene(box);
  const Vec3 p(0.05, 0.02, 0);
  const double h = 1e-5;
  auto moved = [&](double x) { return radiance(box, p + Vec3(x, 0, 0), 0.0); };
  const double exact = (moved(h) - moved(-h)) / (2 * h);
  ASSERT_GT(std::abs(exact), 0.05);
  for (int m = 0; m < 4; ++m) {
    const Estimate e = boundary_estimate(scene, kMethods[m], "floor:translate:1,0,0", p, Vec3(1, 0, 0), 1000000);
    std::printf("[moving receiver] %-14s exact %.5f estimate %.5f +- %.5f\n", kNames[m], exact, e.mean, e.se);
    EXPECT_NEAR(e.mean, exact, 3.5 * e.se) << kNames[m];
    EXPECT_LT(e.se, 0.1 * std::abs(exact)) << kNames[m];
  }
}

}  // namespace qsil
