// The boundary term against analytic oracles (tests/integrators/
// boundary_oracle.h states the oracle): within 3 standard errors at 1e6 samples (two-sided,
// ~99.7% confidence for a correct estimator; fixed seeds). The baselines run the same oracle in
// tests/baselines/baseline_oracle_test.cpp.
#include "integrators/boundary_oracle.h"

#include <gtest/gtest.h>

namespace qsil {
namespace {

using namespace oracle;

const Vec3 kP(0.05, 0.02, 0);  // the receiver point
constexpr double kH = 1e-5;    // step of the central difference of the formula

/// The occluder moves along +x and the receiver point is static: only the occluder's edges move.
void expect_moving_occluder(const Shape& occluder) {
  const Scene scene = oracle_scene(occluder);
  const double exact = (radiance(occluder, kP, kH) - radiance(occluder, kP, -kH)) / (2 * kH);
  const Estimate e = boundary_estimate(scene, Method::Quadric, "occluder:translate:1,0,0", kP, Vec3::Zero(), 1000000);
  ASSERT_GT(std::abs(exact), 0.05);  // a clearly non-zero derivative
  EXPECT_NEAR(e.mean, exact, 3 * e.se) << "exact " << exact << " estimate " << e.mean << " +- " << e.se;
  EXPECT_LT(e.se, 0.05 * std::abs(exact));  // and a useful estimator
}

}  // namespace

// A black square (boundary edges only: the always-candidate list).
TEST(BoundaryOracle, MovingOccluderMatchesLambertsFormulaDerivative) {
  expect_moving_occluder(square("occluder", 0.0, 0.6, -0.2, 0.3, 1.0, true, 1));
}

// A closed cube: its silhouette edges (two faces each) come from the forest's trees, with the
// rejection test, the node importance and the leaf's exact test on the way. No face plane passes
// through the receiver point (that degenerate case makes silhouettes of edge-on faces).
TEST(BoundaryOracle, MovingClosedOccluderSilhouetteMatchesLambertsFormulaDerivative) {
  expect_moving_occluder(closed_box("occluder", Vec3(0.08, -0.09, 0.85), Vec3(0.38, 0.21, 1.15), 1));
}

// The receiver point moves (+x, as on a translating floor) and the occluder and light are static:
// relative velocities make the occluder's AND the light's outlines contribute.
TEST(BoundaryOracle, MovingReceiverSeesStaticOccluderAndLightOutlinesMove) {
  const Shape occluder = square("occluder", 0.0, 0.6, -0.2, 0.3, 1.0, true, 1);
  const Scene scene = oracle_scene(occluder);
  auto moved = [&](double x) { return radiance(occluder, kP + Vec3(x, 0, 0), 0.0); };
  const double exact = (moved(kH) - moved(-kH)) / (2 * kH);
  const Estimate e = boundary_estimate(scene, Method::Quadric, "floor:translate:1,0,0", kP, Vec3(1, 0, 0), 1000000);
  ASSERT_GT(std::abs(exact), 0.05);
  EXPECT_NEAR(e.mean, exact, 3 * e.se) << "exact " << exact << " estimate " << e.mean << " +- " << e.se;
  EXPECT_LT(e.se, 0.05 * std::abs(exact));
}

}  // namespace qsil
