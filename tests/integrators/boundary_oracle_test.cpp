// The boundary term against analytic oracles (issue "boundary term": no Monte Carlo on the
// reference side). A diffuse receiver point p under a uniform square area light, partly blocked
// by a black square occluder: the reflected radiance is
//   L_o = rho * L * (F(light) - F(light ∩ shadow of occluder)),
// F the Lambert form factor of a polygon (cosine_polygon_integral, exact), the shadow being the
// occluder's central projection from p onto the light's plane (a convex polygon clipped to the
// light square). Its derivative is the central difference of that deterministic formula. The
// interior term is zero here (black occluder, constant emission, static or translating receiver
// with a fixed normal), so the boundary estimator alone must match: within 3 standard errors at
// 1e6 samples (two-sided, ~99.7% confidence for a correct estimator; fixed seeds).
#include "edgetree/edge_forest.h"
#include "edgetree/ltc.h"
#include "edgetree/silhouette_sampler.h"
#include "integrators/boundary_term.h"
#include "integrators/render.h"

#include <gtest/gtest.h>

#include <algorithm>

namespace qsil {
namespace {

Shape square(const std::string& id, double x0, double x1, double y0, double y1, double z, bool facing_down, int bsdf) {
  Shape s;
  s.id = id;
  s.type = "rectangle";
  s.mesh.positions = {{x0, y0, z}, {x1, y0, z}, {x1, y1, z}, {x0, y1, z}};
  s.mesh.triangles = facing_down ? std::vector<Eigen::Vector3i>{{0, 2, 1}, {0, 3, 2}}
                                 : std::vector<Eigen::Vector3i>{{0, 1, 2}, {0, 2, 3}};
  s.mesh.normals = vertex_normals(s.mesh);
  s.bsdf = bsdf;
  return s;
}

constexpr double kRho = 0.8, kL = 5.0;
constexpr double kOccX0 = 0.0, kOccX1 = 0.6, kOccY0 = -0.2, kOccY1 = 0.3, kOccZ = 1.0, kLightZ = 2.0;

/// Receiver floor (z = 0), light (z = 2, facing down), black occluder (z = 1).
Scene oracle_scene() {
  Scene s;
  BSDFDesc white, black;
  white.reflectance = Color::Constant(kRho);
  black.reflectance = Color::Zero();
  s.bsdfs = {white, black};
  s.shapes.push_back(square("floor", -20, 20, -20, 20, 0, false, 0));
  Shape light = square("light", -0.5, 0.5, -0.5, 0.5, kLightZ, true, 1);
  light.is_emitter = true;
  light.radiance = Color::Constant(kL);
  s.shapes.push_back(light);
  s.shapes.push_back(square("occluder", kOccX0, kOccX1, kOccY0, kOccY1, kOccZ, true, 1));
  s.max_depth = 2;  // camera -> p -> light: direct illumination only
  return s;
}

/// Convex polygon clipping (Sutherland-Hodgman) in 2D against an axis-aligned box.
std::vector<Vec2> clip_box(std::vector<Vec2> poly, double x0, double x1, double y0, double y1) {
  auto clip = [&](int axis, double bound, double sign) {
    std::vector<Vec2> out;
    for (size_t i = 0; i < poly.size(); ++i) {
      const Vec2 a = poly[i], b = poly[(i + 1) % poly.size()];
      const double fa = sign * (a[axis] - bound), fb = sign * (b[axis] - bound);
      if (fa >= 0) out.push_back(a);
      if ((fa >= 0) != (fb >= 0)) out.push_back(a + (b - a) * (fa / (fa - fb)));
    }
    poly = out;
  };
  clip(0, x0, 1);
  clip(0, x1, -1);
  clip(1, y0, 1);
  clip(1, y1, -1);
  return poly;
}

/// Form factor of a polygon in the plane z = kLightZ seen from p (normal +z).
double form_factor(const std::vector<Vec2>& poly, const Vec3& p) {
  if (poly.size() < 3) return 0;
  std::vector<Vec3> v;
  for (const auto& q : poly) v.push_back(Vec3(q.x(), q.y(), kLightZ) - p);
  return edgetree::cosine_polygon_integral(v);
}

/// L_o at receiver point p with the occluder shifted by dx along x.
double radiance(const Vec3& p, double dx) {
  const std::vector<Vec2> light = {{-0.5, -0.5}, {0.5, -0.5}, {0.5, 0.5}, {-0.5, 0.5}};
  // The occluder's shadow on the light plane: central projection from p (scale (zl - pz)/(zo - pz)).
  const double k = (kLightZ - p.z()) / (kOccZ - p.z());
  std::vector<Vec2> shadow;
  for (const Vec2& c : {Vec2(kOccX0, kOccY0), Vec2(kOccX1, kOccY0), Vec2(kOccX1, kOccY1), Vec2(kOccX0, kOccY1)}) {
    const Vec2 q = c + Vec2(dx, 0) - p.head<2>();
    shadow.push_back(p.head<2>() + k * q);
  }
  const auto blocked = clip_box(shadow, -0.5, 0.5, -0.5, 0.5);
  return kRho * kL * (form_factor(light, p) - form_factor(blocked, p));
}

/// A closed cube (12 outward triangles) centred at c with half-size r: its silhouette edges are
/// two-face edges sampled through the edge forest's trees.
Shape cube(const std::string& id, const Vec3& c, double r, int bsdf) {
  Shape s;
  s.id = id;
  s.type = "obj";
  for (int i = 0; i < 8; ++i) s.mesh.positions.push_back(c + r * Vec3(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1));
  s.mesh.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                      {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  s.mesh.normals = vertex_normals(s.mesh);
  s.bsdf = bsdf;
  return s;
}

constexpr double kCubeR = 0.15;
const Vec3 kCubeC(0.23, 0.06, 1.0);  // no face plane passes through the receiver point

/// 2D convex hull (monotone chain), counter-clockwise.
std::vector<Vec2> hull(std::vector<Vec2> p) {
  std::sort(p.begin(), p.end(), [](const Vec2& a, const Vec2& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  std::vector<Vec2> h(2 * p.size());
  int k = 0;
  auto cross = [](const Vec2& o, const Vec2& a, const Vec2& b) {
    return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
  };
  for (size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (int i = int(p.size()) - 2, t = k + 1; i >= 0; --i) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[size_t(i)]) <= 0) --k;
    h[k++] = p[size_t(i)];
  }
  h.resize(size_t(k - 1));
  return h;
}

/// L_o at p with the cube occluder (instead of the square) shifted by dx along x.
double radiance_cube(const Vec3& p, double dx) {
  const std::vector<Vec2> light = {{-0.5, -0.5}, {0.5, -0.5}, {0.5, 0.5}, {-0.5, 0.5}};
  std::vector<Vec2> shadow;
  for (int i = 0; i < 8; ++i) {
    const Vec3 x = kCubeC + Vec3(dx, 0, 0) + kCubeR * Vec3(i & 1 ? 1 : -1, i & 2 ? 1 : -1, i & 4 ? 1 : -1);
    const double k = (kLightZ - p.z()) / (x.z() - p.z());
    shadow.push_back(p.head<2>() + k * (x.head<2>() - p.head<2>()));
  }
  const auto blocked = clip_box(hull(shadow), -0.5, 0.5, -0.5, 0.5);
  return kRho * kL * (form_factor(light, p) - form_factor(blocked, p));
}

struct Estimate {
  double mean = 0, se = 0;
};

/// The boundary estimator at p (normal +z, viewed from above) with the given dp/dtheta.
Estimate boundary_estimate(const Scene& scene, const std::string& param, const Vec3& p, const Vec3& dp, int n) {
  const std::vector<ParameterSpec> params{parse_parameter(param, scene)};
  const SceneVelocities vel = compute_velocities(scene, params);
  const RayTracer tracer(scene);
  const EnvironmentLight env(scene.environment);
  const AreaLights lights(scene);
  PathContext ctx;
  ctx.scene = &scene;
  ctx.tracer = &tracer;
  ctx.environment = &env;
  ctx.area_lights = &lights;
  ctx.max_depth = scene.max_depth;
  std::vector<edgetree::ForestShapeInput> inputs;
  for (size_t s = 0; s < scene.shapes.size(); ++s) inputs.push_back({&scene.shapes[s].mesh, int(s)});
  const edgetree::EdgeForest forest = edgetree::EdgeForest::build(inputs);
  const std::vector<bool> all(scene.shapes.size(), true);
  edgetree::SilhouetteQuery q;
  q.p = p;
  q.frame = Frame(Vec3(0, 0, 1));
  const Vec3 wo_local(0.3, 0.1, 0.9);
  q.ltc = bsdf_ltc(scene.bsdfs[0], wo_local.normalized());
  q.eligible = dp.isZero() ? &vel.moving : &all;
  Eigen::Matrix<double, 3, 1> dpm = dp;
  Sampler sampler(1234, 0, 0);
  PathStats stats;
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    double v = 0;
    const auto s = edgetree::sample_silhouette(forest, q, [&] { return sampler.next(); });
    if (s.edge && s.pdf > 0) {
      const Vec3 w = (s.edge->p0 + s.t * (s.edge->p1 - s.edge->p0) - p).normalized();
      const Color f = bsdf_eval<double>(scene.bsdfs[0], q.frame.to_local(w), wo_local.normalized());
      Color jump;
      Eigen::Matrix<double, 1, 1> J;
      const Vec3 origin = p + Vec3(0, 0, 1e-6);
      if (edge_jump<1>(ctx, vel, *s.edge, s.t, p, origin, dpm, 1, sampler, stats, jump, J))
        v = f[0] * jump[0] * J[0] / s.pdf;
    }
    sum += v;
    sum2 += v * v;
  }
  Estimate e;
  e.mean = sum / n;
  e.se = std::sqrt(std::max(0.0, sum2 / n - e.mean * e.mean) / (n - 1));
  return e;
}

}  // namespace

// A closed occluder: its silhouette edges (two faces each) come from the forest's trees, with the
// rejection test, the node importance and the leaf's exact test on the way.
TEST(BoundaryOracle, MovingClosedOccluderSilhouetteMatchesLambertsFormulaDerivative) {
  Scene scene = oracle_scene();
  scene.shapes[2] = cube("occluder", kCubeC, kCubeR, 1);
  const Vec3 p(0.05, 0.02, 0);
  const double h = 1e-5;
  const double exact = (radiance_cube(p, h) - radiance_cube(p, -h)) / (2 * h);
  const Estimate e = boundary_estimate(scene, "occluder:translate:1,0,0", p, Vec3::Zero(), 1000000);
  ASSERT_GT(std::abs(exact), 0.05);
  EXPECT_NEAR(e.mean, exact, 3 * e.se) << "exact " << exact << " estimate " << e.mean << " +- " << e.se;
  EXPECT_LT(e.se, 0.05 * std::abs(exact));
}

// The occluder moves (+x) and the receiver point is static: only the occluder's edges move.
TEST(BoundaryOracle, MovingOccluderMatchesLambertsFormulaDerivative) {
  const Scene scene = oracle_scene();
  const Vec3 p(0.05, 0.02, 0);
  const double h = 1e-5;
  const double exact = (radiance(p, h) - radiance(p, -h)) / (2 * h);
  const Estimate e = boundary_estimate(scene, "occluder:translate:1,0,0", p, Vec3::Zero(), 1000000);
  ASSERT_GT(std::abs(exact), 0.05);  // a clearly non-zero derivative
  EXPECT_NEAR(e.mean, exact, 3 * e.se) << "exact " << exact << " estimate " << e.mean << " +- " << e.se;
  EXPECT_LT(e.se, 0.05 * std::abs(exact));  // and a useful estimator
}

// The receiver point moves (+x, as on a translating floor) and the occluder and light are static:
// relative velocities make the occluder's AND the light's outlines contribute.
TEST(BoundaryOracle, MovingReceiverSeesStaticOccluderAndLightOutlinesMove) {
  const Scene scene = oracle_scene();
  const Vec3 p(0.05, 0.02, 0);
  const double h = 1e-5;
  auto moved = [&](double x) { return radiance(p + Vec3(x, 0, 0), 0.0); };
  const double exact = (moved(h) - moved(-h)) / (2 * h);
  const Estimate e = boundary_estimate(scene, "floor:translate:1,0,0", p, Vec3(1, 0, 0), 1000000);
  ASSERT_GT(std::abs(exact), 0.05);
  EXPECT_NEAR(e.mean, exact, 3 * e.se) << "exact " << exact << " estimate " << e.mean << " +- " << e.se;
  EXPECT_LT(e.se, 0.05 * std::abs(exact));
}

}  // namespace qsil
