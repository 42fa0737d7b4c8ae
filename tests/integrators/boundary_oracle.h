#pragma once
// The analytic oracle of the boundary term (shared by tests/integrators/boundary_oracle_test.cpp
// and tests/baselines/baseline_oracle_test.cpp). A diffuse receiver point p (normal +z) under a
// uniform square area light (z = 2, facing down), partly blocked by a black occluder: the
// reflected radiance is
//   L_o = rho * L * (F(light) - F(light ∩ shadow of the occluder)),
// F the exact Lambert form factor of a polygon (cosine_polygon_integral), the shadow the convex
// hull of the occluder's vertices projected from p onto the light's plane. Its derivative is the
// central difference of that deterministic formula; no Monte Carlo on the reference side. The
// interior term is zero (black occluder, constant emission, fixed receiver normal), so the
// boundary estimator alone must match.
#include "integrators/boundary_setup.h"
#include "qsil/edgetree/edge_forest.h"
#include "qsil/edgetree/ltc.h"
#include "qsil/integrators/boundary_term.h"
#include "qsil/integrators/estimator.h"

#include <algorithm>

namespace qsil::oracle {

inline constexpr double kRho = 0.8, kL = 5.0, kLightZ = 2.0;

/// An axis-aligned square [x0,x1]x[y0,y1] at height z, two triangles.
inline Shape square(const std::string& id, double x0, double x1, double y0, double y1, double z, bool facing_down,
                    int bsdf) {
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

/// A closed axis-aligned box [lo, hi] (12 outward triangles): its silhouette edges are two-face
/// edges, sampled through the edge forest's trees.
inline Shape closed_box(const std::string& id, const Vec3& lo, const Vec3& hi, int bsdf) {
  Shape s;
  s.id = id;
  s.type = "obj";
  for (int c = 0; c < 8; ++c)
    s.mesh.positions.emplace_back(c & 1 ? hi.x() : lo.x(), c & 2 ? hi.y() : lo.y(), c & 4 ? hi.z() : lo.z());
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    s.mesh.triangles.emplace_back(q[0], q[1], q[2]);
    s.mesh.triangles.emplace_back(q[0], q[2], q[3]);
  }
  s.mesh.normals = vertex_normals(s.mesh);
  s.bsdf = bsdf;
  return s;
}

/// Receiver floor (z = 0, white), light (z = 2, facing down), and the given occluder (black); the
/// camera centre (the Hough origin of the v-sphere methods) above and to the side.
inline Scene oracle_scene(Shape occluder) {
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
  occluder.id = "occluder";
  occluder.bsdf = 1;
  s.shapes.push_back(occluder);
  s.camera.to_world.block<3, 1>(0, 3) = Vec3(0.3, -2.0, 3.0);
  s.max_depth = 2;  // camera -> p -> light: direct illumination only
  return s;
}

/// Convex polygon clipping (Sutherland-Hodgman) in 2D against an axis-aligned box.
inline std::vector<Vec2> clip_box(std::vector<Vec2> poly, double x0, double x1, double y0, double y1) {
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

/// 2D convex hull (monotone chain), counter-clockwise.
inline std::vector<Vec2> convex_hull(std::vector<Vec2> p) {
  std::sort(p.begin(), p.end(),
            [](const Vec2& a, const Vec2& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
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

/// Form factor of a polygon in the plane z = kLightZ seen from p (normal +z).
inline double form_factor(const std::vector<Vec2>& poly, const Vec3& p) {
  if (poly.size() < 3) return 0;
  std::vector<Vec3> v;
  for (const auto& q : poly) v.push_back(Vec3(q.x(), q.y(), kLightZ) - p);
  return edgetree::cosine_polygon_integral(v);
}

/// L_o at receiver point p with the occluder's vertices shifted by dx along x.
inline double radiance(const Shape& occluder, const Vec3& p, double dx) {
  const std::vector<Vec2> light = {{-0.5, -0.5}, {0.5, -0.5}, {0.5, 0.5}, {-0.5, 0.5}};
  std::vector<Vec2> shadow;
  for (const Vec3& x : occluder.mesh.positions) {
    const double k = (kLightZ - p.z()) / (x.z() - p.z());
    shadow.push_back(p.head<2>() + k * (x.head<2>() + Vec2(dx, 0) - p.head<2>()));
  }
  return kRho * kL * (form_factor(light, p) - form_factor(clip_box(convex_hull(shadow), -0.5, 0.5, -0.5, 0.5), p));
}

struct Estimate {
  double mean = 0, se = 0;
};

/// The boundary estimator of `method` at p (normal +z, viewed from above) with dp/dtheta = dp,
/// n traversals (EdgeSampler::sample_set, as the renderer: split edges included), fixed seed.
inline Estimate boundary_estimate(const Scene& scene, Method method, const std::string& param, const Vec3& p,
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
  const BoundarySetup setup = build_boundary_setup(scene, method);
  const edgetree::EdgeSampler* edge_sampler = setup.sampler.get();
  const std::vector<bool> all(scene.shapes.size(), true);
  edgetree::SilhouetteQuery q;
  q.p = p;
  q.frame = Frame(Vec3(0, 0, 1));
  const Vec3 wo_local = Vec3(0.3, 0.1, 0.9).normalized();
  q.ltc = edgetree::bsdf_ltc(scene.bsdfs[0], wo_local);
  q.eligible = dp.isZero() ? &vel.moving : &all;
  const Eigen::Matrix<double, 3, 1> dpm = dp;
  Sampler sampler(1234, 0, 0);
  PathStats stats;
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    double v = 0;
    edgetree::SilhouetteSampleSet set;
    edge_sampler->sample_set(q, [&] { return sampler.next(); }, set);
    for (int k = 0; k < set.count; ++k) {
      const edgetree::SilhouetteSample& s = set.samples[size_t(k)];
      const Vec3 w = (s.edge->p0 + s.t * (s.edge->p1 - s.edge->p0) - p).normalized();
      const Color f = bsdf_eval<double>(scene.bsdfs[0], q.frame.to_local(w), wo_local);
      Eigen::Matrix<double, 1, 1> J;
      const EdgeJumpInputs in{.edge = *s.edge,
                              .t = s.t,
                              .p = p,
                              .vis_origin = p + Vec3(0, 0, 1e-6),
                              .through_back_faces = false,
                              .own = OwnFace{},
                              .segments = 1};
      if (const std::optional<Color> jump = edge_jump<1>(ctx, vel, in, dpm, sampler, stats, J))
        v += f[0] * (*jump)[0] * J[0] / s.pdf;
    }
    sum += v;
    sum2 += v * v;
  }
  Estimate e;
  e.mean = sum / n;
  e.se = std::sqrt(std::max(0.0, sum2 / n - e.mean * e.mean) / (n - 1));
  return e;
}

}  // namespace qsil::oracle
