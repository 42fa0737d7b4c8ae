/// @file baseline_oracle_test.cpp
/// Unbiasedness of every --boundary estimator against an analytic oracle (the scene builder and
/// estimator of tests/integrators/boundary_oracle_test.cpp, copied and extended): a diffuse
/// receiver point p under a uniform square area light, partly blocked by a black CLOSED BOX (so
/// that the trees hold convex edges, some of them silhouettes from the Hough origin = the camera
/// centre and some not, besides the always-candidate outlines of the light and the floor):
///   L_o = rho L (F(light) - F(light ∩ shadow)),
/// F the exact Lambert form factor, the shadow the convex hull of the box's eight corners
/// projected from p onto the light's plane. Its derivative is the central difference of this
/// deterministic formula. The interior term is zero (black occluder, constant emission, fixed
/// receiver normal), so the boundary estimator alone must match within 3.5 standard errors
/// (two-sided, ~99.95% per case for a correct estimator; 8 cases), fixed seeds.

#include "edgetree/edge_forest.h"
#include "edgetree/ltc.h"
#include "integrators/boundary_term.h"
#include "integrators/edge_sampler_factory.h"
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
constexpr double kBoxX0 = 0.0, kBoxX1 = 0.6, kBoxY0 = -0.2, kBoxY1 = 0.3, kBoxZ0 = 0.9, kBoxZ1 = 1.1, kLightZ = 2.0;

/// An axis-aligned closed box, outward counter-clockwise faces.
Shape box(const std::string& id, int bsdf) {
  Shape s;
  s.id = id;
  s.type = "obj";
  for (int c = 0; c < 8; ++c)
    s.mesh.positions.emplace_back(c & 1 ? kBoxX1 : kBoxX0, c & 2 ? kBoxY1 : kBoxY0, c & 4 ? kBoxZ1 : kBoxZ0);
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    s.mesh.triangles.emplace_back(q[0], q[1], q[2]);
    s.mesh.triangles.emplace_back(q[0], q[2], q[3]);
  }
  s.mesh.normals = vertex_normals(s.mesh);
  s.bsdf = bsdf;
  return s;
}

/// Receiver floor (z = 0), light (z = 2, facing down), black box (z in [0.9, 1.1]); the camera
/// (only its centre matters here: the Hough origin of the v-sphere methods) above and to the side.
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
  s.shapes.push_back(box("occluder", 1));
  s.camera.to_world.block<3, 1>(0, 3) = Vec3(0.3, -2.0, 3.0);
  s.max_depth = 2;
  return s;
}

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

/// Convex hull (Andrew's monotone chain), counter-clockwise.
std::vector<Vec2> convex_hull(std::vector<Vec2> pts) {
  std::sort(pts.begin(), pts.end(), [](const Vec2& a, const Vec2& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  auto cross = [](const Vec2& o, const Vec2& a, const Vec2& b) {
    return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
  };
  std::vector<Vec2> h(2 * pts.size());
  size_t k = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], pts[i]) <= 0) --k;
    h[k++] = pts[i];
  }
  for (size_t i = pts.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross(h[k - 2], h[k - 1], pts[i]) <= 0) --k;
    h[k++] = pts[i];
  }
  h.resize(k - 1);
  return h;
}

double form_factor(const std::vector<Vec2>& poly, const Vec3& p) {
  if (poly.size() < 3) return 0;
  std::vector<Vec3> v;
  for (const auto& q : poly) v.push_back(Vec3(q.x(), q.y(), kLightZ) - p);
  return edgetree::cosine_polygon_integral(v);
}

/// L_o at receiver point p with the box shifted by dx along x.
double radiance(const Vec3& p, double dx) {
  const std::vector<Vec2> light = {{-0.5, -0.5}, {0.5, -0.5}, {0.5, 0.5}, {-0.5, 0.5}};
  std::vector<Vec2> proj;
  for (int c = 0; c < 8; ++c) {
    const Vec3 x(c & 1 ? kBoxX1 : kBoxX0, c & 2 ? kBoxY1 : kBoxY0, c & 4 ? kBoxZ1 : kBoxZ0);
    const double k = (kLightZ - p.z()) / (x.z() - p.z());
    proj.push_back(p.head<2>() + k * (x.head<2>() + Vec2(dx, 0) - p.head<2>()));
  }
  const auto blocked = clip_box(convex_hull(proj), -0.5, 0.5, -0.5, 0.5);
  return kRho * kL * (form_factor(light, p) - form_factor(blocked, p));
}

struct Estimate {
  double mean = 0, se = 0;
};

Estimate boundary_estimate(const Scene& scene, BoundaryMethod method, const std::string& param, const Vec3& p,
                           const Vec3& dp, int n) {
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
  const auto sampler_ptr = make_edge_sampler(method, scene, forest);
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
    const auto s = sampler_ptr->sample(q, [&] { return sampler.next(); });
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

const BoundaryMethod kMethods[] = {BoundaryMethod::Quadric, BoundaryMethod::VSphere, BoundaryMethod::VSphereSolid,
                                   BoundaryMethod::Uniform};
const char* kNames[] = {"quadric", "vsphere", "vsphere-solid", "uniform"};

}  // namespace

// The box moves (+x), the receiver point is static: only the box's edges move.
TEST(BaselineOracle, MovingBoxMatchesLambertsFormulaDerivative) {
  const Scene scene = oracle_scene();
  const Vec3 p(0.05, 0.02, 0);
  const double h = 1e-5;
  const double exact = (radiance(p, h) - radiance(p, -h)) / (2 * h);
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
  const Scene scene = oracle_scene();
  const Vec3 p(0.05, 0.02, 0);
  const double h = 1e-5;
  auto moved = [&](double x) { return radiance(p + Vec3(x, 0, 0), 0.0); };
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
