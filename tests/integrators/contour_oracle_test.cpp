// The boundary term at a glossy shading point with a contour set (qsil/edgetree/contour_set.h)
// against brute force over all edges. Scene: a static GGX mirror (alpha 0.02) at z = 0 under a
// constant environment (radiance 1), and a black occluder translating along +y whose outline
// crosses the mirror's lobe at p. Foreground radiance 0 and background 1 make the integrand
// deterministic, so the reference is a quadrature: the sum over every discontinuity edge from p
// of the integral over t (midpoint rule, 4000 points, the integrand evaluated by the renderer's
// own edge_jump) of f_s . jump . J.
// Estimators (fixed seeds, 200000 traversals each, as the renderer calls them through
// for_each_boundary_sample):
// - with the contour set: the traversal for the edges outside the set (its points on the set's
//   edges dropped) plus one point on the set's edges (split edges left to their own point);
// - the same with two traversals per vertex (sppi 2);
// - the traversal alone (no contour index).
// Each must agree with the reference within 4 standard errors (two-sided, ~99.99 % for a correct
// estimator) with a standard error below 1 % of it: a 5 % bias is caught.
// Cases (each a point p whose contour set's core the occluder's outline crosses):
// - at the mirror's p (the lobe's core):
//   - a smooth-shaded icosphere (1280 faces, radius 0.5): its contour set must carry at least
//     half the reference (so dropping the traversal's points on it, or not, is a difference of
//     that size), and the contour estimator's variance must be at least 2x lower;
//   - an open quad, whose four outline edges are loose always-candidates, split (estimated at
//     every traversal with probability 1): the contour set holds split edges, which must stay the
//     splitting's (counting them in both strategies is a bias of their share of the reference,
//     asserted above 50 %);
// - at a diffuse p on a static floor under a small quad light (0.4 x 0.4 at height 2.5, half-angle
//   0.11 rad from p; the light's core, boundary_term.h light_core), the icosphere half across the
//   light's cone from p (a penumbra): its contour set must carry at least half the reference and
//   cut the variance at least 2x;
// - the same point sliding fast (dp/dtheta = (8, 8, 0), 11.3 x the occluder's speed, as a
//   camera ray's hit at a grazing angle slides; boundary_split): every traversal is split into 3,
//   which must agree with the reference as above and cut the per-vertex variance at least 2x
//   against the unsplit estimator (no splitting, split_speed 0), which must agree too.
#include "integrators/boundary_oracle.h"
#include "integrators/boundary_setup.h"
#include "integrators/light_setup.h"
#include "qsil/edgetree/quadric_sampler.h"
#include "test_scenes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

namespace qsil {
namespace {

const Vec3 kP = Vec3::Zero();                  // the shading point on the mirror
const Vec3 kWo = Vec3(-1, 0, 1).normalized();  // toward the viewer
// The reflected direction from p is (1, 0, 1)/sqrt 2.
const Vec3 kAxisPoint = kP + 2.5 * Vec3(1, 0, 1).normalized();

/// The mirror, the environment and `occluder` (black, id "occluder").
Scene glossy_scene(Shape occluder) {
  Scene s;
  BSDFDesc mirror, black;
  mirror.type = BSDFDesc::Type::RoughConductor;
  mirror.alpha = 0.02;
  mirror.specular_reflectance = Color::Ones();
  black.reflectance = Color::Zero();
  s.bsdfs = {mirror, black};
  s.shapes.push_back(oracle::square("mirror", -5, 5, -5, 5, 0, false, 0));
  occluder.id = "occluder";
  occluder.bsdf = 1;
  s.shapes.push_back(occluder);
  s.environment.type = Environment::Type::Constant;
  s.environment.radiance = Color::Ones();
  s.camera = test::look_at(kP + 3.0 * kWo, kP, 40, 16, 16, 1);
  s.max_depth = 2;  // camera -> p -> edge point -> environment
  return s;
}

/// A static diffuse floor (z = 0, white) under a small square light (0.4 x 0.4 at z = 2.5,
/// facing down, radiance 10), `occluder` (black, id "occluder") and no environment; the camera
/// as in glossy_scene (p on the floor).
Scene light_scene(Shape occluder) {
  Scene s;
  BSDFDesc white, black;
  white.reflectance = Color::Constant(0.8);
  black.reflectance = Color::Zero();
  s.bsdfs = {white, black};
  s.shapes.push_back(oracle::square("floor", -5, 5, -5, 5, 0, false, 0));
  Shape light = oracle::square("light", -0.2, 0.2, -0.2, 0.2, 2.5, true, 1);
  light.is_emitter = true;
  light.radiance = Color::Constant(10.0);
  s.shapes.push_back(light);
  occluder.id = "occluder";
  occluder.bsdf = 1;
  s.shapes.push_back(occluder);
  s.camera = test::look_at(kP + 3.0 * kWo, kP, 40, 16, 16, 1);
  s.max_depth = 2;  // camera -> p -> edge point -> light
  return s;
}

struct Mean {
  double mean = 0, se = 0, var = 0;
};

/// What a case measured: the reference, the contour set's share of it, whether the set holds a
/// split edge, and the three estimates.
struct OracleResult {
  double reference = 0, contour_share = 0;
  bool contour_has_split_edge = false;
  int split = 1;  ///< boundary_split at p
  Mean with, with_two, without;
  Mean unsplit;  ///< with the contour set, without splitting (only when p moves)
};

/// The case at the camera ray's hit p, moving at `p_velocity` (dp/dtheta, world) while the
/// occluder translates along +y at unit speed.
OracleResult run_oracle(const Scene& scene, const Vec3& p_velocity = Vec3::Zero()) {
  OracleResult r;
  const std::vector<ParameterSpec> params{parse_parameter("occluder:translate:0,1,0", scene)};
  const SceneVelocities vel = compute_velocities(scene, params);
  const RayTracer tracer(scene);
  const LightSetup lights(scene);
  const PathContext ctx = lights.context(scene, tracer);
  BoundarySetup boundary;
  BoundaryContext boundary_ctx;
  PrimaryEdges primary;
  SetupReport setup;
  set_up_boundary_term(scene, tracer, Method::Quadric, &vel, vel.moving, 1, lights.environment, boundary, boundary_ctx, primary,
                       setup);
  EXPECT_TRUE(boundary.contours && boundary_ctx.contours == boundary.contours.get())
      << "a scene with a glossy BSDF or a quad light has contour sets";
  if (!boundary_ctx.contours) return r;

  // ---- The shading point: the camera ray's hit on the mirror at p.
  const Vec3 origin = scene.camera.origin(), dir = (kP - origin).normalized();
  const Hit hit = tracer.intersect(origin, dir);
  EXPECT_TRUE(hit.valid() && hit.shape == 0);
  const PrimalView pv{&scene};
  const SurfaceInteraction<double> si = make_interaction(pv, hit, origin, dir, tracer.local_origin());
  const ShadingPoint<double> sp = make_shading_point(ctx, si, -dir);
  const Vec3 wo_local = sp.frame_value.to_local(-dir);
  edgetree::SilhouetteQuery q = boundary_query(boundary_ctx, si, sp, wo_local, nullptr);
  const bool p_moves = p_velocity != Vec3::Zero();
  q.eligible = p_moves ? &boundary_ctx.all : &boundary_ctx.moving;  // as BoundaryHook: at a moving p every edge moves
  q.velocities = &vel;
  q.dp.setZero();
  q.dp.col(0) = p_velocity;
  q.velocity_scale = boundary_ctx.velocity_scale;
  const Eigen::Matrix<double, 3, 1> dp = p_velocity;
  r.split = boundary_split(boundary_ctx, q);
  const Vec3 p = value(si.p);

  // ---- The contour set at p (the probe as the renderer makes it) and the split edges.
  int rays = 0;
  const edgetree::ContourProbe probe = contour_probe(ctx, *boundary.contours, si, Vec3(-dir), q, rays);
  EXPECT_GT(probe.count, 0) << "the core's axis or ring must meet the occluder";
  std::vector<const edgetree::Edge*> contour;
  boundary.contours->contour_edges(probe, p, q.eligible, contour);
  EXPECT_FALSE(contour.empty());
  for (const edgetree::Edge* e : edgetree::split_edges(*boundary.forest, q, edgetree::NodeTest::DualBoxAndQuadrics))
    r.contour_has_split_edge |= std::find(contour.begin(), contour.end(), e) != contour.end();

  // ---- Reference: quadrature over every discontinuity edge of the moving occluder.
  Sampler rng(1, 0, 0);
  PathStats stats;
  auto integrand = [&](const edgetree::Edge& e, double t) {
    const Vec3 w = (e.p0 + t * (e.p1 - e.p0) - p).normalized();
    const Color f = bsdf_eval<double>(*sp.bsdf, sp.frame_value.to_local(w), wo_local);
    if ((f == 0).all()) return 0.0;
    Eigen::Matrix<double, 1, 1> J;
    const EdgeJumpInputs in{.edge = e,
                            .t = t,
                            .p = p,
                            .vis_origin = spawn_origin(si, w),
                            .through_back_faces = leaves_below(si, Vec3(-dir), w),
                            .own = OwnFace{},
                            .segments = 1};
    const std::optional<Color> jump = edge_jump<1>(ctx, vel, in, dp, rng, stats, J);
    if (!jump) return 0.0;
    return f[0] * (*jump)[0] * J[0];
  };
  auto quadrature = [&](const edgetree::Edge& e, int n) {
    double sum = 0;
    for (int i = 0; i < n; ++i) sum += integrand(e, (i + 0.5) / n);
    return sum / n;
  };
  double coarse = 0, on_contour = 0;
  int edges = 0;
  for (const auto* arr : {&boundary.forest->edges(), &boundary.forest->always_edges()})
    for (const edgetree::Edge& e : *arr) {
      if (!q.is_eligible(e.shape) || !edgetree::is_discontinuity(e, p)) continue;
      const double fine = quadrature(e, 4000);
      r.reference += fine;
      coarse += quadrature(e, 2000);
      if (std::find(contour.begin(), contour.end(), &e) != contour.end()) on_contour += fine;
      ++edges;
    }
  r.contour_share = on_contour / r.reference;
  std::printf(
      "[ measured ] reference %.6g over %d discontinuity edges (2000-point rule %.6g); contour set: %zu edges, "
      "%.3f of the reference%s\n",
      r.reference, edges, coarse, contour.size(), r.contour_share,
      r.contour_has_split_edge ? ", split edges among them" : "");
  EXPECT_GT(std::abs(r.reference), 1e-3);
  EXPECT_NEAR(coarse, r.reference, 1e-3 * std::abs(r.reference)) << "the quadrature has not converged";

  // ---- The estimators, as the renderer runs them.
  auto estimate = [&](const BoundaryContext& b, uint64_t seed) {
    Sampler sampler(seed, 0, 0);
    PathStats st;
    const int n = int(200000 / b.sppi);
    double sum = 0, sum2 = 0;
    for (int i = 0; i < n; ++i) {
      double v = 0;
      Eigen::Matrix<double, 1, 1> J;
      const BoundaryVertex<double> vertex{.si = si,
                                          .sp = sp,
                                          .query = q,
                                          .wo_local = wo_local,
                                          .throughput = Color::Ones(),
                                          .segments = 1,
                                          .traversals = int(b.sppi)};
      for_each_boundary_sample(
          ctx, b, vertex, sampler, st,
          [&](const edgetree::Edge& e, double t, const Vec3& gv) {
            J = edge_point_jacobian<1>(vel, e, t, gv, dp);
            return !J.isZero(0.0);
          },
          [&](const edgetree::Edge&, double, const Color& weight, const Vec3&) { v += weight[0] * J[0]; });
      sum += v;
      sum2 += v * v;
    }
    Mean m;
    m.mean = sum / n;
    m.var = std::max(0.0, sum2 / n - m.mean * m.mean);
    m.se = std::sqrt(m.var / (n - 1));
    return m;
  };
  r.with = estimate(boundary_ctx, 11);
  BoundaryContext two = boundary_ctx;
  two.sppi = 2;
  r.with_two = estimate(two, 13);
  BoundaryContext plain = boundary_ctx;
  plain.contours = nullptr;
  r.without = estimate(plain, 12);
  std::printf(
      "[ measured ] with the contour set %.6g +- %.3g (two traversals per vertex %.6g +- %.3g), traversal "
      "alone %.6g +- %.3g; variance ratio %.2f; split %d\n",
      r.with.mean, r.with.se, r.with_two.mean, r.with_two.se, r.without.mean, r.without.se, r.without.var / r.with.var,
      r.split);
  std::vector<Mean> estimates{r.with, r.with_two, r.without};
  if (p_moves) {
    BoundaryContext unsplit = boundary_ctx;
    unsplit.split_speed = 0;
    r.unsplit = estimate(unsplit, 14);
    estimates.push_back(r.unsplit);
    std::printf("[ measured ] unsplit %.6g +- %.3g; per-vertex variance unsplit / split %.2f\n", r.unsplit.mean,
                r.unsplit.se, r.unsplit.var / r.with.var);
  }
  for (const Mean& m : estimates) {
    EXPECT_NEAR(m.mean, r.reference, 4 * m.se);
    EXPECT_LT(m.se, 0.01 * std::abs(r.reference));
  }
  return r;
}

TEST(ContourOracle, GlossyPointMatchesBruteForceOverAllEdges) {
  // The sphere's centre 0.42 off the lobe's axis (radius 0.5): the axis meets it near its outline.
  Shape sphere;
  sphere.type = "obj";
  sphere.mesh = test::icosphere(3, kAxisPoint + Vec3(0, 0.42, 0), 0.5);
  const OracleResult r = run_oracle(glossy_scene(sphere));
  EXPECT_GT(r.contour_share, 0.5) << "the contour set must carry most of the integral for the test to have power";
  EXPECT_GT(r.without.var / r.with.var, 2.0);
}

TEST(ContourOracle, SplitEdgesInTheContourSetStayTheSplittings) {
  // An open quad across the lobe, facing p, its lower edge 0.1 below the lobe's axis: the axis
  // meets it, and the walks reach its outline.
  const Vec3 n = (kP - kAxisPoint).normalized(), side = Vec3(0, 1, 0).cross(n).normalized();
  Shape quad;
  quad.type = "rectangle";
  const Vec3 c = kAxisPoint + Vec3(0, 0.4, 0);
  quad.mesh.positions = {c - 0.5 * side - Vec3(0, 0.5, 0), c + 0.5 * side - Vec3(0, 0.5, 0),
                         c + 0.5 * side + Vec3(0, 0.5, 0), c - 0.5 * side + Vec3(0, 0.5, 0)};
  quad.mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  if (quad.mesh.face_cross(0).dot(n) < 0) quad.mesh.triangles = {{0, 2, 1}, {0, 3, 2}};
  quad.mesh.normals = vertex_normals(quad.mesh);
  const OracleResult r = run_oracle(glossy_scene(quad));
  EXPECT_TRUE(r.contour_has_split_edge) << "the test needs a split edge in the contour set";
  EXPECT_GT(r.contour_share, 0.5) << "counting it twice must be a bias larger than the noise";
}

TEST(ContourOracle, PointUnderASmallLightMatchesBruteForceOverAllEdges) {
  // The light's cone from p is about the +z axis (half-angle 0.11 rad); the sphere (radius 0.3,
  // centre 0.25 off the axis at height 1.2) covers the axis, its outline 0.04 rad beyond it.
  Shape sphere;
  sphere.type = "obj";
  sphere.mesh = test::icosphere(3, Vec3(0, 0.25, 1.2), 0.3);
  const OracleResult r = run_oracle(light_scene(sphere));
  EXPECT_GT(r.contour_share, 0.5) << "the contour set must carry most of the integral for the test to have power";
  EXPECT_GT(r.without.var / r.with.var, 2.0);
}

TEST(ContourOracle, AFastSlidingPointSplitsItsTraversals) {
  // The penumbra of the previous case, p sliding along the floor at 11.3 x the occluder's speed,
  // obliquely (along x alone the slide's part of the integral is 0 by symmetry): speed 11.3
  // against the quadric method's split_speed 4 is 3 traversals for each one.
  Shape sphere;
  sphere.type = "obj";
  sphere.mesh = test::icosphere(3, Vec3(0, 0.25, 1.2), 0.3);
  const OracleResult r = run_oracle(light_scene(sphere), Vec3(8, 8, 0));
  EXPECT_EQ(r.split, 3) << "the test needs the split at p";
  EXPECT_GT(r.unsplit.var / r.with.var, 2.0) << "3 traversals per vertex must cut the per-vertex variance";
}

}  // namespace
}  // namespace qsil
