/// @file ltc_test.cpp
/// Tests of the LTC approximation of qsil's GGX and of the spherical polygon integrals
/// (edgetree/ltc.h).
///
/// Quadratures: test::sphere_quadrature centred on the lobe (cells shrink toward the centre),
/// 1500 x 1024 cells for hemisphere integrals; for polygon integrals a cap around the polygon's
/// centre containing it, 1500 x 1500 cells, with an exact inside test (the indicator's boundary
/// error is < 1e-3 relative for the polygons used, measured by refining 2x; tolerances below
/// take 2-5x margin). No randomness apart from fixed-seed TestRng draws of the polygons and points.

#include "qsil/edgetree/ltc.h"
#include "qsil/bsdf.h"

#include "chi2.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace qsil::edgetree {
namespace {

using test::TestRng;

Vec3 dir_from_angles(double theta, double phi) {
  return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

/// Centre of the LTC lobe: M * z (forward matrix).
Vec3 ltc_center(const LTC& l) {
  const Vec3 c = l.M_inv.inverse() * Vec3::UnitZ();
  return c.normalized();
}

struct LobeCase {
  double alpha;
  double theta_deg;
  double phi;  // azimuth of wo, exercises the rotation
};

const LobeCase kCases[] = {{1.0, 0, 0.0},   {0.5, 30, 1.0}, {0.3, 60, -2.0}, {0.1, 45, 0.5},
                           {0.02, 20, 2.5}, {0.3, 80, 0.3}, {0.05, 75, -1.0}};

double ggx_albedo(double alpha, const Vec3& wo) {
  const Vec3 mirror(-wo.x(), -wo.y(), wo.z());
  return test::integrate_sphere(mirror, 1500, 1024, [&](const Vec3& w) { return ggx_eval_cos<double>(alpha, w, wo); });
}

// norm * D integrated over the hemisphere ~= the albedo of our GGX (the table's norm is the albedo;
// the difference is the LTC's mass below the shading horizon, which ltc_eval drops).
TEST(LTCTest, HemisphereIntegralMatchesGGXAlbedo) {
  for (const LobeCase& c : kCases) {
    const Vec3 wo = dir_from_angles(c.theta_deg * kPi / 180.0, c.phi);
    const LTC l = ltc_ggx(c.alpha, wo);
    const double albedo = ggx_albedo(c.alpha, wo);
    const double ltc_int =
        l.norm * test::integrate_sphere(ltc_center(l), 1500, 1024, [&](const Vec3& w) { return ltc_eval(l, w); });
    // The stored norm is the albedo itself (128^2 stratified samples at the node, then bilinear).
    EXPECT_NEAR(l.norm, albedo, 0.01 * albedo) << "alpha " << c.alpha << " theta " << c.theta_deg;
    // Below-horizon mass: small for moderate angles, larger at grazing.
    const double tol = c.theta_deg >= 70 ? 0.10 : 0.03;
    EXPECT_NEAR(ltc_int, albedo, tol * albedo) << "alpha " << c.alpha << " theta " << c.theta_deg;
    RecordProperty("hemisphere_rel_err_a" + std::to_string(c.alpha) + "_t" + std::to_string(int(c.theta_deg)),
                   std::to_string((ltc_int - albedo) / albedo));
    std::printf("[LTC] alpha %.3g theta %2.0f: albedo %.5f, norm %.5f, norm*int_H D %.5f (rel %+.4f)\n", c.alpha,
                c.theta_deg, albedo, l.norm, ltc_int, (ltc_int - albedo) / albedo);
  }
}

TEST(LTCTest, DiffuseIsTheCosine) {
  const LTC l = ltc_diffuse();
  const Vec3 w = dir_from_angles(0.7, 1.3);
  EXPECT_NEAR(ltc_eval(l, w), w.z() / kPi, 1e-15);
  EXPECT_NEAR(ltc_eval(l, 3.0 * w), w.z() / kPi, 1e-15);  // scale-free
  EXPECT_EQ(ltc_eval(l, Vec3(0.3, 0.2, -0.5)), 0.0);
}

TEST(LTCTest, BelowSurfaceViewHasZeroNorm) {
  EXPECT_EQ(ltc_ggx(0.3, Vec3(0.2, 0.1, -0.9)).norm, 0.0);
  EXPECT_EQ(ltc_ggx(0.3, Vec3(0.0, 0.0, 0.0)).norm, 0.0);
}

// A random spherical quad, star-shaped around a centre direction (so simple), with a few that
// straddle the shading horizon.
std::vector<Vec3> random_quad(TestRng& rng, const Vec3& center, double max_radius) {
  const Frame f(center.normalized());
  double angles[4];
  const double base = rng.uniform() * 2 * kPi;
  for (int k = 0; k < 4; ++k) angles[k] = base + (k + 0.2 + 0.6 * rng.uniform()) * (kPi / 2);
  std::vector<Vec3> q;
  for (double a : angles) {
    const double r = std::tan(max_radius * (0.4 + 0.6 * rng.uniform()));
    // Points at random distances from the apex: the routines must be scale-free.
    const double scale = 0.5 + 3.0 * rng.uniform();
    q.push_back(scale * f.to_world(Vec3(r * std::cos(a), r * std::sin(a), 1.0)));
  }
  return q;
}

bool in_triangle(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double s0 = d.dot(a.cross(b)), s1 = d.dot(b.cross(c)), s2 = d.dot(c.cross(a));
  return (s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0);
}

/// Integral of f over the star-shaped (around `center`) spherical polygon q, by a cap quadrature.
double integrate_polygon(const std::vector<Vec3>& q, const Vec3& center, const std::function<double(const Vec3&)>& f,
                         int n = 1500) {
  const Vec3 c = center.normalized();
  double cap = 0;
  for (const Vec3& v : q) cap = std::max(cap, std::acos(std::clamp(v.normalized().dot(c), -1.0, 1.0)));
  return test::integrate_sphere(
      c, n, n,
      [&](const Vec3& d) {
        for (size_t i = 0; i < q.size(); ++i)
          if (in_triangle(c, q[i], q[(i + 1) % q.size()], d)) return f(d);
        return 0.0;
      },
      std::min(kPi, 1.05 * cap));
}

// The polygon integral equals the quadrature of D over the polygon (exact formula, so only the
// quadrature error remains), and approximates the quadrature of the true f cos (LTC error).
TEST(LTCTest, PolygonIntegralMatchesQuadrature) {
  TestRng rng(20250611);
  double worst_ltc_vs_ggx = 0;
  int n_checked = 0;
  for (const LobeCase& c : kCases) {
    const Vec3 wo = dir_from_angles(c.theta_deg * kPi / 180.0, c.phi);
    const LTC l = ltc_ggx(c.alpha, wo);
    const Vec3 lobe = ltc_center(l);
    for (int k = 0; k < 3; ++k) {
      // Quads near the lobe (sizes relative to the lobe width), one centred off the lobe.
      const double width = std::max(0.05, 1.5 * c.alpha);
      const Vec3 off =
          Frame(lobe).to_world(dir_from_angles(width * (k == 2 ? 1.2 : 0.3) * rng.uniform(), 6.28 * rng.uniform()));
      const std::vector<Vec3> q = random_quad(rng, off, std::min(1.2, width * (1.0 + k)));
      const double exact = l.norm * ltc_polygon_integral(l, q);
      const double quad_ltc = l.norm * integrate_polygon(q, off, [&](const Vec3& w) { return ltc_eval(l, w); });
      const double quad_ggx =
          integrate_polygon(q, off, [&](const Vec3& w) { return ggx_eval_cos<double>(c.alpha, w.normalized(), wo); });
      EXPECT_NEAR(exact, quad_ltc, 2e-3 * quad_ltc + 1e-6)
          << "alpha " << c.alpha << " theta " << c.theta_deg << " k " << k;
      // LTC vs the true BSDF: judged relative to the albedo (a polygon holding a tiny part of the
      // lobe has a large relative error that does not matter for importance).
      const double err = std::abs(exact - quad_ggx) / l.norm;
      worst_ltc_vs_ggx = std::max(worst_ltc_vs_ggx, err);
      ++n_checked;
      std::printf(
          "[LTC] alpha %.3g theta %2.0f quad %d: LTC %.5f, quadrature of D %.5f, GGX %.5f (|diff|/albedo %.4f)\n",
          c.alpha, c.theta_deg, k, exact, quad_ltc, quad_ggx, err);
      EXPECT_LT(err, 0.10) << "alpha " << c.alpha << " theta " << c.theta_deg << " k " << k;
    }
  }
  std::printf("[LTC] worst |LTC - GGX| / albedo over %d quads: %.4f\n", n_checked, worst_ltc_vs_ggx);
}

TEST(LTCTest, LambertFormFactor) {
  // A polygon on the horizon covering the whole upper hemisphere: 1, either winding.
  std::vector<Vec3> h = {{1, 1, 0}, {-1, 1, 0}, {-1, -1, 0}, {1, -1, 0}};
  EXPECT_NEAR(cosine_polygon_integral(h), 1.0, 1e-14);
  std::vector<Vec3> hr(h.rbegin(), h.rend());
  EXPECT_NEAR(cosine_polygon_integral(hr), 1.0, 1e-14);
  // A huge square at height 1, and the same square much lower down: nearly 1.
  std::vector<Vec3> big = {{1e4, 1e4, 1}, {-1e4, 1e4, 1}, {-1e4, -1e4, 1}, {1e4, -1e4, 1}};
  EXPECT_NEAR(cosine_polygon_integral(big), 1.0, 1e-3);
  // Square of side 2a = 1 centred above at height 1, by hand: each edge subtends
  // angle 2 atan(a / sqrt(1 + a^2)) and its plane's normal has z = a / sqrt(1 + a^2), so
  // F = 4 * (1/2pi) * 2 (a/s) atan(a/s), s = sqrt(1 + a^2).
  const double x = 0.5;
  const double s = std::sqrt(1 + x * x);
  const double f_quadrant = (1 / (2 * kPi)) * (2 * x / s * std::atan(x / s));
  std::vector<Vec3> sq = {{0.5, 0.5, 1}, {-0.5, 0.5, 1}, {-0.5, -0.5, 1}, {0.5, -0.5, 1}};
  EXPECT_NEAR(cosine_polygon_integral(sq), 4 * f_quadrant, 1e-14);
  // A small quad: ~ cos * solid angle / pi.
  const Vec3 c = dir_from_angles(0.7, 0.4);
  const Frame f(c);
  const double e = 1e-3;
  std::vector<Vec3> small = {f.to_world(Vec3(e, e, 1)), f.to_world(Vec3(-e, e, 1)), f.to_world(Vec3(-e, -e, 1)),
                             f.to_world(Vec3(e, -e, 1))};
  const double omega = polygon_solid_angle(small);
  EXPECT_NEAR(omega, 4 * e * e, 1e-5 * 4 * e * e);
  EXPECT_NEAR(cosine_polygon_integral(small), c.z() * omega / kPi, 1e-5 * c.z() * omega / kPi);
  // Below the horizon: 0. Straddling: only the upper part counts.
  std::vector<Vec3> below = {{1, 0, -1}, {0, 1, -1}, {-1, 0, -1}};
  EXPECT_EQ(cosine_polygon_integral(below), 0.0);
  std::vector<Vec3> strad = {{1, -1, -1}, {1, 1, -1}, {1, 1, 1}, {1, -1, 1}};
  std::vector<Vec3> upper = {{1, -1, 0}, {1, 1, 0}, {1, 1, 1}, {1, -1, 1}};
  EXPECT_NEAR(cosine_polygon_integral(strad), cosine_polygon_integral(upper), 1e-15);
  EXPECT_GT(cosine_polygon_integral(upper), 0.0);
  // Equal to the LTC integral with the diffuse LTC.
  EXPECT_NEAR(ltc_polygon_integral(ltc_diffuse(), strad), cosine_polygon_integral(strad), 1e-15);
}

// The fast paths (fast_atan2, which node importance uses) agree with the exact ones to the
// approximation's accuracy, an absolute error below 1e-5 rad per angle: the form factor (a sum of
// at most 8 arc angles / 2 pi after clipping) within 2e-5, the solid angle (2 atan2 per fan
// triangle, 2 triangles) within 5e-5 sr, over random quads around and across the horizon, for
// the cosine lobe (diffuse: no transform) and GGX lobes. Also the diffuse LTC's integral equals
// the cosine integral computed without the LTC (an independent path). Worst differences printed.
TEST(LTCTest, FastAnglesAgreeWithExactOnes) {
  TestRng rng(77);
  double worst_ff = 0, worst_omega = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec3 center = dir_from_angles(1.6 * rng.uniform(), 6.28 * rng.uniform());
    const std::vector<Vec3> q = random_quad(rng, center, 0.05 + 1.1 * rng.uniform());
    const LTC l = i % 2 ? ltc_diffuse() : ltc_ggx(0.02 + rng.uniform(), dir_from_angles(1.4 * rng.uniform(), 0.3));
    const double exact = ltc_polygon_integral(l, q, false), fast = ltc_polygon_integral(l, q, true);
    ASSERT_NEAR(fast, exact, 2e-5) << "case " << i;
    if (i % 2) {
      ASSERT_NEAR(exact, cosine_polygon_integral(q), 1e-12 * exact + 1e-15) << "case " << i;
    }
    const double omega = polygon_solid_angle(q, false), omega_fast = polygon_solid_angle(q, true);
    ASSERT_NEAR(omega_fast, omega, 5e-5) << "case " << i;
    worst_ff = std::max(worst_ff, std::abs(fast - exact));
    worst_omega = std::max(worst_omega, std::abs(omega_fast - omega));
  }
  std::printf("[LTC] fast angles: worst |difference| form factor %.2e, solid angle %.2e sr\n", worst_ff, worst_omega);
}

TEST(LTCTest, SolidAngle) {
  std::vector<Vec3> octant = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  EXPECT_NEAR(polygon_solid_angle(octant), kPi / 2, 1e-14);
  std::vector<Vec3> octant_scaled = {{5, 0, 0}, {0, 0, 0.1}, {0, 2, 0}};  // other winding, scaled
  EXPECT_NEAR(polygon_solid_angle(octant_scaled), kPi / 2, 1e-14);
  // A cube face seen from the cube's centre: 4 pi / 6.
  std::vector<Vec3> face = {{1, -1, 1}, {1, 1, 1}, {-1, 1, 1}, {-1, -1, 1}};
  EXPECT_NEAR(polygon_solid_angle(face), 4 * kPi / 6, 1e-13);
}

/// Solid angle of the box as the sum over its faces visible from p (they project disjointly).
double box_solid_angle_by_faces(const Box3& b, const Vec3& p, double (*measure)(std::span<const Vec3>)) {
  double sum = 0;
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      const double plane = side ? b.hi[axis] : b.lo[axis];
      const bool visible = side ? p[axis] > plane : p[axis] < plane;
      if (!visible) continue;
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      std::vector<Vec3> f;
      for (int k = 0; k < 4; ++k) {
        Vec3 x;
        x[axis] = plane;
        x[u] = (k == 1 || k == 2) ? b.hi[u] : b.lo[u];
        x[v] = (k >= 2) ? b.hi[v] : b.lo[v];
        f.push_back(x - p);
      }
      sum += measure(f);
    }
  }
  return sum;
}

TEST(LTCTest, BoxSilhouettePolygon) {
  TestRng rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    const double scale = std::pow(10.0, -3 + 6 * rng.uniform());  // scale-free: 1e-3 .. 1e3
    Box3 b;
    const Vec3 c(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5);
    Vec3 ext(rng.uniform(), rng.uniform(), rng.uniform());
    if (trial % 10 == 0) ext[trial % 3] = 0.0;  // flat boxes (planar patches) too
    b.expand(scale * (c - 0.5 * ext));
    b.expand(scale * (c + 0.5 * ext));
    Vec3 p;
    do {
      p = scale * Vec3(4 * rng.uniform() - 2, 4 * rng.uniform() - 2, 4 * rng.uniform() - 2);
    } while (((p.array() >= b.lo.array()) && (p.array() <= b.hi.array())).all());
    const BoxSilhouette s = box_silhouette_polygon(b, p);
    ASSERT_FALSE(s.inside);
    ASSERT_LE(s.polygon.count, 6);
    const double omega = polygon_solid_angle(s.polygon.span());
    const double by_faces =
        box_solid_angle_by_faces(b, p, [](std::span<const Vec3> poly) { return polygon_solid_angle(poly); });
    EXPECT_NEAR(omega, by_faces, 1e-10 * std::max(by_faces, 1e-12)) << "trial " << trial;
    // Lambert form factor with the horizon clip (z = normal at p) equals the sum over faces too.
    const double ff = cosine_polygon_integral(s.polygon.span());
    const double ff_faces = box_solid_angle_by_faces(b, p, cosine_polygon_integral);
    EXPECT_NEAR(ff, ff_faces, 1e-10 * std::max(ff_faces, 1e-12) + 1e-15) << "trial " << trial;
  }
  // Monte Carlo: fraction of uniform directions whose ray hits the box = omega / (4 pi).
  Box3 b;
  b.expand(Vec3(0.2, -0.3, 0.5));
  b.expand(Vec3(1.0, 0.4, 1.3));
  const Vec3 p(-0.4, 0.9, 0.1);
  const BoxSilhouette s = box_silhouette_polygon(b, p);
  const double omega = polygon_solid_angle(s.polygon.span());
  const int n = 400000;
  int hits = 0;
  for (int i = 0; i < n; ++i) {
    const Vec2 u = rng.uniform2();
    const double z = 1 - 2 * u.x(), r = std::sqrt(std::max(0.0, 1 - z * z)), ph = 2 * kPi * u.y();
    const Vec3 d(r * std::cos(ph), r * std::sin(ph), z);
    double t0 = 0, t1 = kInf;
    for (int k = 0; k < 3; ++k) {
      const double a = (b.lo[k] - p[k]) / d[k], c = (b.hi[k] - p[k]) / d[k];
      t0 = std::max(t0, std::min(a, c));
      t1 = std::min(t1, std::max(a, c));
    }
    hits += t0 <= t1;
  }
  const double frac = omega / (4 * kPi);
  const double sigma = std::sqrt(frac * (1 - frac) / n);
  EXPECT_NEAR(double(hits) / n, frac, 4 * sigma);  // 4 sigma: false-failure probability 6e-5
  // Inside (and on the boundary): flagged.
  EXPECT_TRUE(box_silhouette_polygon(b, b.center()).inside);
  EXPECT_TRUE(box_silhouette_polygon(b, b.lo).inside);
  EXPECT_FALSE(box_silhouette_polygon(Box3{}, p).inside);
  EXPECT_EQ(box_silhouette_polygon(Box3{}, p).polygon.count, 0);
}

TEST(LTCTest, HalfspaceClipIntersectsWithLight) {
  // Clipping a big polygon by the four planes through the apex and a light quad's edges leaves
  // the light's own solid angle ([QSS] 3.6: Omega(B_p) intersected with Omega(light)).
  std::vector<Vec3> light = {{-0.2, -0.1, 1}, {0.3, -0.1, 1}, {0.3, 0.2, 1.2}, {-0.2, 0.2, 1.2}};
  std::vector<Vec3> big = {{-5, -5, 1}, {5, -5, 1}, {5, 5, 1}, {-5, 5, 1}};
  SmallPolygon cur;
  for (const Vec3& v : big) cur.push(v);
  for (size_t i = 0; i < light.size(); ++i) {
    const Vec3 n = light[i].cross(light[(i + 1) % light.size()]);  // inward for this winding
    cur = clip_polygon_to_halfspace(cur.span(), n);
  }
  EXPECT_NEAR(polygon_solid_angle(cur.span()), polygon_solid_angle(light), 1e-12);
}

}  // namespace
}  // namespace qsil::edgetree
