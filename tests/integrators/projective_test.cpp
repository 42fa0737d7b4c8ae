// Projective sampling (integrators/projective_boundary.h, Method::Projective):
// - the directions of a boundary segment: drawn only where the edge is a silhouette, uniformly
//   over its lune (an integral estimated with them equals the same integral by uniform sphere
//   directions), the whole sphere for a boundary edge;
// - the estimator agrees with finite differences where the secondary boundary term is a shadow
//   edge seen from static points (penumbra-sign) and a static light's outline seen from moving
//   points (plane-light: the shading point's velocity, trap 2);
// - its secondary term equals the quadric method's (itself checked against finite differences
//   elsewhere) where finite differences at res 8 are too noisy to judge: an intersection curve
//   (sunk-sphere), the creases of a rotating flat-shaded cube (faceted-cube), at depth 2
//   (shading points seen in a mirror: the walk toward the camera and its adjoint steps), and where
//   the walk has two connections to choose from (penumbra-wall: its reservoir). With the same seed the two share the
//   interior and the primary term bit for bit, so their difference is the difference of the two secondary estimates
//   alone;
// - its guide (a grid over the segments' unit cube, off by default) has a normalised density,
//   never below its uniform share, sampled as stated; the agreements hold without it and with it
//   (penumbra-sign, plane-light, sunk-sphere, penumbra-wall);
// - its octree guide (from projected seeds) likewise: normalised, never below its uniform share,
//   sampled as stated, denser where the points are; the projection finds, from most hits on a
//   smooth sphere, a boundary segment on an edge that is a silhouette from the viewpoint, with its
//   direction from the viewpoint through the edge point, and boundary_segment inverts exactly; the
//   guided estimates stay unbiased (penumbra-sign against finite differences, penumbra-wall
//   against the quadric method);
// - reverse mode and --largest-samples refuse it (runs in parts, guided or not, combine to the
//   whole run bit for bit: distributed_test.cpp).
// Confidence: agreement with finite differences is |difference| < 3 standard errors (99.7 %), with
// the quadric method a t-test over 8 seeds (99 %); fixed seeds, and a power assertion each: the
// standard error is a few percent of the value compared.
#include "estimator_runs.h"
#include "integrators/light_setup.h"
#include "integrators/projective_boundary.h"
#include "integrators/silhouette_projection.h"
#include "qsil/error.h"
#include "qsil/integrators/estimator.h"
#include "qsil/integrators/reverse.h"
#include "qsil/parameters.h"
#include "qsil/ray_tracer.h"
#include "qsil/sampling.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

namespace qsil {
namespace {

using test::derivative_sum;
using test::message_of;
using test::quiet;
using test::Sum;

/// The grid guide and the octree guide (both off by default).
const ProjectiveGuiding kGrid{.resolution = 16};
const ProjectiveGuiding kOctree{.octree = true};

/// An edge along +x whose faces have unit normals n0 and n1 (both perpendicular to +x).
edgetree::Edge edge_with_normals(const Vec3& n0, const Vec3& n1, edgetree::EdgeClass cls, int f1 = 1) {
  edgetree::Edge e;
  e.p0 = Vec3(0, 0, 0);
  e.p1 = Vec3(1, 0, 0);
  e.v0 = 0;
  e.v1 = 1;
  e.f0 = 0;
  e.f1 = f1;
  e.q0 << n0, 0.0;
  if (f1 >= 0) e.q1 << n1, 0.0;
  e.length = 1;
  e.cls = cls;
  return e;
}

// An integral over the lune by the lune's own directions equals the same integral by uniform
// sphere directions times the lune's indicator, and every drawn direction lies in the lune (a
// wedge on the wrong side, or the measure of the whole sphere, would fail one of the two).
TEST(ProjectiveDirections, UniformOverTheSilhouetteLune) {
  const Vec3 n0 = Vec3(0, 0.6, 0.8), n1 = Vec3(0, -0.6, 0.8);  // 1.287 rad apart
  const edgetree::Edge e = edge_with_normals(n0, n1, edgetree::EdgeClass::Convex);
  EXPECT_NEAR(edge_direction_measure(e), 4 * std::acos(0.28), 1e-12);
  const Vec3 c(0.7, -1.1, 0.4);
  auto f = [&](const Vec3& w) { return std::exp(w.dot(c)) * (1.0 + w.x() * w.x()); };
  Sampler sampler(7, 0, 0);
  const int n = 400000;
  double lune = 0, lune2 = 0, sphere = 0, sphere2 = 0;
  int outside = 0;
  for (int i = 0; i < n; ++i) {
    const EdgeDirection d = sample_edge_direction(e, sampler.next2());
    outside += !((n0.dot(d.w)) * (n1.dot(d.w)) < 0);
    const double a = f(d.w) / d.pdf;
    lune += a;
    lune2 += a * a;
    const Vec3 w = square_to_uniform_sphere(sampler.next2());
    const double b = (n0.dot(w) * n1.dot(w) < 0) ? f(w) / uniform_sphere_pdf() : 0.0;
    sphere += b;
    sphere2 += b * b;
  }
  EXPECT_EQ(outside, 0);
  const double ml = lune / n, ms = sphere / n;
  const double se = std::sqrt((lune2 / n - ml * ml) / n + (sphere2 / n - ms * ms) / n);
  std::printf("integral over the lune: lune directions %.5f, sphere directions %.5f, se %.2g\n", ml, ms, se);
  EXPECT_NEAR(ml, ms, 3 * se);
  EXPECT_LT(se, 0.01 * ms) << "power";
}

TEST(ProjectiveDirections, BoundaryEdgesAndCreasesTakeTheWholeSphere) {
  const edgetree::Edge boundary = edge_with_normals(Vec3(0, 0, 1), Vec3::Zero(), edgetree::EdgeClass::Boundary, -1);
  EXPECT_DOUBLE_EQ(edge_direction_measure(boundary), 4 * kPi);
  edgetree::Edge crease = edge_with_normals(Vec3(0, 0.6, 0.8), Vec3(0, -0.6, 0.8), edgetree::EdgeClass::Convex);
  crease.crease = true;
  EXPECT_DOUBLE_EQ(edge_direction_measure(crease), 4 * kPi);
  crease.retired = true;
  EXPECT_EQ(edge_direction_measure(crease), 0.0);
  EXPECT_EQ(sample_edge_direction(crease, Vec2(0.3, 0.3)).pdf, 0.0);
}

// A guide's density integrates to 1 over the unit cube, is at least the uniform share everywhere
// (cells that learnt nothing included), and its samples fall in each cell as often as the density
// says (a chi-square test over the cells, 99.9 %).
TEST(SegmentGuides, DensityIsNormalisedPositiveAndSampledAsStated) {
  const int r = 4, cells = r * r * r;
  std::vector<double> weights(size_t(cells), 0.0);
  weights[5] = 3.0;
  weights[17] = 1.0;
  weights[63] = 0.5;
  const SegmentGuide guide(r, weights, 0.2);
  double integral = 0, smallest = 1e300;
  for (int c = 0; c < cells; ++c) {
    const Vec3 centre((c % r + 0.5) / r, ((c / r) % r + 0.5) / r, (c / (r * r) + 0.5) / r);
    ASSERT_EQ(guide.cell(centre), c);
    integral += guide.density(centre) / cells;
    smallest = std::min(smallest, guide.density(centre));
  }
  EXPECT_NEAR(integral, 1.0, 1e-12);
  EXPECT_NEAR(smallest, 0.2, 1e-12);
  Sampler sampler(3, 0, 0);
  const int n = 200000;
  std::vector<int> count(size_t(cells), 0);
  for (int i = 0; i < n; ++i) {
    const double choose = sampler.next(), pick = sampler.next();
    const Vec3 within(sampler.next(), sampler.next(), sampler.next());
    const Vec3 u = guide.sample(choose, pick, within);
    ASSERT_TRUE((u.array() >= 0).all() && (u.array() < 1).all());
    ++count[size_t(guide.cell(u))];
  }
  double chi2 = 0;
  for (int c = 0; c < cells; ++c) {
    const Vec3 centre((c % r + 0.5) / r, ((c / r) % r + 0.5) / r, (c / (r * r) + 0.5) / r);
    const double expected = n * guide.density(centre) / cells;
    chi2 += (count[size_t(c)] - expected) * (count[size_t(c)] - expected) / expected;
  }
  EXPECT_LT(chi2, 103.4) << "chi-square, 63 degrees of freedom, 99.9 %";
  EXPECT_TRUE(SegmentGuide(r, std::vector<double>(size_t(cells), 0.0), 0.2).density(Vec3(0.3, 0.3, 0.3)) == 1.0)
      << "a guide that learnt nothing is uniform";
}

// The octree's density, like the grid's, integrates to 1 and is at least the uniform share; it is
// higher where the points crowd (the guide learns); its samples fall in each of the 8^3 cells of a
// coarse grid as often as the density says (chi-square, 511 degrees of freedom, 99.9 %: 620), and
// in each leaf expected to hold at least 20 of them within 5 standard deviations (a leaf's
// samples drawn in a sibling's box fail it); the same points give the same guide.
TEST(SegmentGuides, OctreeDensityIsNormalisedPositiveAndSampledAsStated) {
  Sampler points_rng(7, 0, 0);
  std::vector<Vec3> points;
  std::vector<double> values;
  for (int i = 0; i < 600; ++i) {  // a cluster near (0.1, 0.2, 0.3) with value 2, and a uniform background of 0.1
    const bool cluster = i < 500;
    const Vec3 r(points_rng.next(), points_rng.next(), points_rng.next());
    points.push_back(cluster ? Vec3(0.1, 0.2, 0.3) + 0.05 * r : r);
    values.push_back(cluster ? 2.0 : 0.1);
  }
  const int depth = 6, fine = 1 << depth, coarse = 8;
  const SegmentGuide guide = SegmentGuide::octree(points, values, depth, 8, 0.2);
  ASSERT_FALSE(guide.uniform());
  ASSERT_GT(guide.cells(), 8);
  // The density is constant on each leaf, and every leaf is a union of the fine grid's cells.
  double integral = 0, smallest = 1e300;
  std::vector<double> expected(size_t(coarse * coarse * coarse), 0.0), leaf(size_t(guide.cells()), 0.0);
  for (int z = 0; z < fine; ++z)
    for (int y = 0; y < fine; ++y)
      for (int x = 0; x < fine; ++x) {
        const Vec3 centre((x + 0.5) / fine, (y + 0.5) / fine, (z + 0.5) / fine);
        const double d = guide.density(centre) / (double(fine) * fine * fine);
        integral += d;
        smallest = std::min(smallest, guide.density(centre));
        expected[size_t(x * coarse / fine + coarse * (y * coarse / fine + coarse * (z * coarse / fine)))] += d;
        leaf[size_t(guide.cell(centre))] += d;
      }
  EXPECT_NEAR(integral, 1.0, 1e-9);
  EXPECT_NEAR(smallest, 0.2, 1e-12);
  EXPECT_GT(guide.density(Vec3(0.12, 0.22, 0.32)), 10 * guide.density(Vec3(0.8, 0.8, 0.8)));
  Sampler sampler(3, 0, 0);
  const int n = 200000;
  std::vector<int> count(expected.size(), 0), leaf_count(leaf.size(), 0);
  for (int i = 0; i < n; ++i) {
    const double choose = sampler.next(), pick = sampler.next();
    const Vec3 within(sampler.next(), sampler.next(), sampler.next());
    const Vec3 u = guide.sample(choose, pick, within);
    ASSERT_TRUE((u.array() >= 0).all() && (u.array() < 1).all());
    ++count[size_t(int(u.x() * coarse) + coarse * (int(u.y() * coarse) + coarse * int(u.z() * coarse)))];
    ++leaf_count[size_t(guide.cell(u))];
  }
  double chi2 = 0;
  for (size_t c = 0; c < expected.size(); ++c)
    chi2 += (count[c] - n * expected[c]) * (count[c] - n * expected[c]) / (n * expected[c]);
  EXPECT_LT(chi2, 620.0) << "chi-square, 511 degrees of freedom, 99.9 %";
  int judged = 0;
  for (size_t c = 0; c < leaf.size(); ++c) {
    if (n * leaf[c] < 20) continue;
    ++judged;
    EXPECT_NEAR(leaf_count[c], n * leaf[c], 5 * std::sqrt(n * leaf[c])) << "leaf " << c;
  }
  EXPECT_GT(judged, 20);
  const SegmentGuide again = SegmentGuide::octree(points, values, depth, 8, 0.2);
  for (int i = 0; i < 1000; ++i) {
    const Vec3 u(sampler.next(), sampler.next(), sampler.next());
    ASSERT_EQ(again.cell(u), guide.cell(u));
    ASSERT_EQ(again.density(u), guide.density(u));
  }
  EXPECT_EQ(SegmentGuide::octree(points, std::vector<double>(points.size(), 0.0), depth, 8, 0.2)
                .density(Vec3(0.11, 0.21, 0.31)),
            1.0)
      << "a guide that learnt nothing is uniform";
}

/// sunk-sphere with the sphere lifted clear of the floor (a smooth-shaded icosphere of radius 0.5
/// at (0, 0.6, 0)), its edge set and boundary sample space, and a path context.
struct LiftedSphere {
  const Scene scene =
      load_scene(test::data_file("tests/data/gradient/sunk-sphere.xml"), {{"res", "8"}, {"height", "0.6"}});
  const edgetree::EdgeSet edge_set = edgetree::EdgeSet::build(edgetree::forest_inputs(scene));
  const ProjectiveEdges edges = make_projective_edges(edge_set, std::vector<bool>(scene.shapes.size(), true));
  const RayTracer tracer{scene};
  const LightSetup lights{scene};
  const PathContext ctx = lights.context(scene, tracer);
};

// boundary_segment(invert_boundary_segment(segment)) is the segment again, for segments of lune
// edges (the sphere's) and of whole-sphere edges (the floor's boundary).
TEST(ProjectiveProjection, InvertsBoundarySegments) {
  const LiftedSphere s;
  Sampler sampler(11, 0, 0);
  int inverted = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3 u(sampler.next(), sampler.next(), sampler.next());
    const BoundarySegment seg = boundary_segment(s.edges, u);
    if (!(seg.pdf > 0)) continue;
    const std::optional<Vec3> back = invert_boundary_segment(s.edges, seg.edge, seg.t, seg.direction.w);
    ASSERT_TRUE(back.has_value()) << i;
    const BoundarySegment again = boundary_segment(s.edges, *back);
    ASSERT_EQ(again.edge, seg.edge) << i;
    ASSERT_NEAR(again.t, seg.t, 1e-9) << i;
    ASSERT_LT((again.direction.w - seg.direction.w).norm(), 1e-9) << i;
    ++inverted;
  }
  EXPECT_GT(inverted, 19000);
  // A direction outside a lune edge's lune has no u.
  size_t lune = 0;
  while (lune < s.edges.edges.size() && !(edge_direction_measure(*s.edges.edges[lune]) < 4 * kPi)) ++lune;
  ASSERT_LT(lune, s.edges.edges.size());
  const edgetree::Edge& e = *s.edges.edges[lune];
  const Vec3 outward = (e.q0.head<3>() + e.q1.head<3>()).normalized();  // both faces front-facing: no silhouette
  EXPECT_FALSE(invert_boundary_segment(s.edges, lune, 0.5, outward).has_value());
}

// From viewpoints on the floor and around the sphere, rays at random points of the sphere: the
// projection (walk and Newton jump) finds a segment for at least 90 % of them (94 %; without the
// walk and the jump, only hits on a silhouette's own triangles would: 0 of 1000), on an edge that
// is a silhouette from the viewpoint, with its direction from the viewpoint through the edge point.
TEST(ProjectiveProjection, FindsSilhouettesSeenFromTheViewpoint) {
  const LiftedSphere s;
  const TriangleEdges tri = triangle_edges(s.scene, s.edges);
  const Vec3 centre(0, 0.6, 0);
  Sampler sampler(13, 0, 0);
  PathStats stats;
  int hits = 0, projected = 0;
  for (const Vec3& x : {Vec3(1.2, 0, 0.3), Vec3(-0.4, 0, 1.5), Vec3(0.3, 2.0, 0.2), Vec3(2.0, 0.8, -1.0)}) {
    for (int i = 0; i < 250; ++i) {
      const Vec3 target = centre + 0.45 * square_to_uniform_sphere(sampler.next2());
      const Vec3 d = (target - x).normalized();
      const Hit hit = s.tracer.intersect(x, d);
      if (!hit.valid() || s.scene.shapes[size_t(hit.shape)].id != "sphere") continue;
      ++hits;
      const std::optional<Vec3> u = project_seed(s.ctx, s.edges, tri, x, hit, sampler, stats);
      if (!u) continue;
      ++projected;
      const BoundarySegment seg = boundary_segment(s.edges, *u);
      ASSERT_GT(seg.pdf, 0.0);
      const edgetree::Edge& e = *s.edges.edges[seg.edge];
      ASSERT_TRUE(edgetree::edge_is_silhouette(e, x));
      const Vec3 y = e.p0 + seg.t * (e.p1 - e.p0);
      ASSERT_LT((seg.direction.w - (y - x).normalized()).norm(), 1e-9);
    }
  }
  std::printf("%d of %d hits projected\n", projected, hits);
  ASSERT_GT(hits, 500);
  EXPECT_GT(projected, 0.9 * hits);
}

// The octree guide trained on penumbra-sign's projected seeds (the occluder's outline seen from
// the floor toward the light) has learnt something: hundreds of seeds, tens of leaves, and a
// density above twice the uniform one somewhere (549 seeds, 43 leaves, 4.75; the uniform guide,
// which would pass the agreement tests below too, is 1 everywhere).
TEST(ProjectiveProjection, OctreeGuideLearnsFromProjectedSeeds) {
  const Scene scene = load_scene(test::data_file("tests/data/gradient/penumbra-sign.xml"), {{"res", "8"}});
  const SceneVelocities vel = compute_velocities(scene, parse_parameters({"occluder:translate:0,1,0"}, scene));
  const edgetree::EdgeSet edge_set = edgetree::EdgeSet::build(edgetree::forest_inputs(scene));
  const ProjectiveEdges edges = make_projective_edges(edge_set, vel.moving);
  const RayTracer tracer{scene};
  const LightSetup lights{scene};
  const PathContext ctx = lights.context(scene, tracer);
  PathStats stats;
  long long seeds = 0;
  const SegmentGuide guide = train_projected_guide(ctx, vel, edges, kOctree, 1, stats, &seeds);
  Sampler sampler(17, 0, 0);
  double largest = 0;
  for (int i = 0; i < 4096; ++i) {
    const Vec3 within(sampler.next(), sampler.next(), sampler.next());
    largest = std::max(largest, guide.density(guide.sample(1.0, sampler.next(), within)));
  }
  std::printf("%lld seeds, %d leaves, largest density %.3g\n", seeds, guide.cells(), largest);
  EXPECT_GT(seeds, 300);
  EXPECT_GT(guide.cells(), 8);
  EXPECT_GT(largest, 2.0);
  EXPECT_EQ(train_projected_guide(ctx, vel, edges, ProjectiveGuiding{}, 1, stats).cells(), 0) << "off by default";
}

/// Projective sampling against central finite differences on `file` at res 8.
void expect_agrees_with_fd(const std::string& file, const std::string& param, int spp, int fd_spp, double power,
                           const std::map<std::string, std::string>& defines = {}, ProjectiveGuiding guiding = {}) {
  auto d = defines;
  d["res"] = "8";
  const Scene scene = load_scene(test::data_file(file), d);
  const auto params = parse_parameters({param}, scene);
  const Sum fd = derivative_sum(Estimator(scene, EstimatorConfig::finite_differences(params)).run(quiet(fd_spp, 41)));
  EstimatorConfig config = EstimatorConfig::gradient(params, Method::Projective);
  config.projective_guiding = guiding;
  const Sum g = derivative_sum(Estimator(scene, config).run(quiet(spp, 42)));
  const double se = std::hypot(g.se, fd.se);
  std::printf("%s %s: projective %.4g +- %.3g, fd %.4g +- %.3g, z %.2f\n", file.c_str(), param.c_str(), g.value, g.se,
              fd.value, fd.se, (g.value - fd.value) / se);
  EXPECT_NEAR(g.value, fd.value, 3 * se);
  EXPECT_LT(se, power * std::abs(fd.value)) << "power";
}

TEST(Projective, ShadowEdgesAgreeWithFiniteDifferences) {
  expect_agrees_with_fd("tests/data/gradient/penumbra-sign.xml", "occluder:translate:0,1,0", 4096, 4096, 0.04, {},
                        kGrid);
}

// The whole derivative is the static light's outline moving relative to the rising floor's
// points: with p's velocity left out, projective sampling gives 0 here.
TEST(Projective, StaticEdgesSeenFromMovingPointsAgreeWithFiniteDifferences) {
  expect_agrees_with_fd("tests/data/gradient/plane-light.xml", "floor:translate:0,1,0", 16384, 4096, 0.04);
}

/// Projective sampling's secondary term against the quadric method's on `file` at res 8: with the
/// same seed both runs share the interior and the primary term bit for bit (the boundary terms
/// draw from streams of their own), so p - q per seed is the difference of the two secondary
/// estimates alone; its mean over 8 seeds must be 0 by a t-test with 7 degrees of freedom at
/// |t| < 3.5 (99 %), and its standard error below `power` x the boundary term (quadric - none,
/// first seed). The quadric
/// method's own agreement with finite differences on these scenes: gradient_vs_fd_test.cpp and
/// intersection_curves_test.cpp.
void expect_secondary_term_equals_quadric(const std::string& file, const std::string& param, int spp, double power,
                                          const std::map<std::string, std::string>& defines = {},
                                          ProjectiveGuiding guiding = {}) {
  auto d = defines;
  d["res"] = "8";
  const Scene scene = load_scene(test::data_file(file), d);
  const auto params = parse_parameters({param}, scene);
  const Estimator quadric(scene, EstimatorConfig::gradient(params, Method::Quadric));
  EstimatorConfig config = EstimatorConfig::gradient(params, Method::Projective);
  config.projective_guiding = guiding;
  const Estimator projective(scene, config);
  const int seeds = 8;
  double diff = 0, diff2 = 0, boundary = 0;
  for (int s = 0; s < seeds; ++s) {
    const RenderOptions o = quiet(spp, uint64_t(51 + s));
    const double q = derivative_sum(quadric.run(o)).value, p = derivative_sum(projective.run(o)).value;
    if (s == 0)
      boundary = q - derivative_sum(Estimator(scene, EstimatorConfig::gradient(params, Method::None)).run(o)).value;
    diff += p - q;
    diff2 += (p - q) * (p - q);
  }
  diff /= seeds;
  const double se = std::sqrt((diff2 / seeds - diff * diff) / (seeds - 1));
  std::printf("%s %s: boundary term (quadric) %.4g, projective - quadric %.4g +- %.3g\n", file.c_str(), param.c_str(),
              boundary, diff, se);
  EXPECT_NEAR(diff, 0.0, 3.5 * se);
  EXPECT_LT(se, power * std::abs(boundary)) << "power";
}

TEST(Projective, IntersectionCurvesEqualTheQuadricMethod) {
  expect_secondary_term_equals_quadric("tests/data/gradient/sunk-sphere.xml", "sphere:translate:0,1,0", 256, 0.05, {},
                                       kGrid);
}

TEST(Projective, CreasesOfARotatingFacetedCubeEqualTheQuadricMethod) {
  expect_secondary_term_equals_quadric("tests/data/gradient/faceted-cube.xml", "cube:rotate:0,1,0", 2048, 0.06);
}

// The sphere of sunk-sphere-mirror is seen only in the mirror (GGX alpha 0.2 here): its boundary
// term lies at shading points on the mirror (connections of the walk's first vertex) and at points
// on the floor and the sphere seen in it (second vertex, an adjoint step through the mirror).
TEST(Projective, SecondaryTermThroughAMirrorEqualsTheQuadricMethod) {
  expect_secondary_term_equals_quadric("tests/data/gradient/sunk-sphere-mirror.xml", "sphere:translate:0,1,0", 512,
                                       0.05, {{"alpha", "0.2"}});
}

// A floor point in a penumbra and the wall points it lights are both seen by the camera: the walk
// has two connections and keeps one, weighted by their count (without that weight the
// difference is +0.2, 8 % of the term).
TEST(Projective, ReservoirOfConnectionsEqualsTheQuadricMethod) {
  expect_secondary_term_equals_quadric("tests/data/gradient/penumbra-wall.xml", "occluder:translate:0,1,0", 512, 0.03);
}

// With the grid guide the estimates stay unbiased (its density divides every weight).
TEST(Projective, GuidedAgreesWithFiniteDifferencesAndTheQuadricMethod) {
  expect_agrees_with_fd("tests/data/gradient/plane-light.xml", "floor:translate:0,1,0", 16384, 4096, 0.04, {}, kGrid);
  expect_secondary_term_equals_quadric("tests/data/gradient/penumbra-wall.xml", "occluder:translate:0,1,0", 512, 0.03,
                                       {}, kGrid);
}

// So with the octree guide.
TEST(Projective, OctreeGuidedAgreesWithFiniteDifferencesAndTheQuadricMethod) {
  expect_agrees_with_fd("tests/data/gradient/penumbra-sign.xml", "occluder:translate:0,1,0", 4096, 4096, 0.04, {},
                        kOctree);
  expect_secondary_term_equals_quadric("tests/data/gradient/penumbra-wall.xml", "occluder:translate:0,1,0", 512, 0.03,
                                       {}, kOctree);
}

TEST(Projective, RefusesWhatItCannotDo) {
  const Scene scene = load_scene(test::data_file("tests/data/gradient/plane-light.xml"), {{"res", "4"}});
  const auto params = parse_parameters({"floor:translate:0,1,0"}, scene);
  RenderOptions o = quiet(1, 1);
  o.largest_samples = 2;
  EXPECT_EQ(message_of([&] { Estimator(scene, EstimatorConfig::gradient(params, Method::Projective)).run(o); }),
            "projective: the largest samples' paths are not traced for this method");
  EXPECT_EQ(message_of([&] {
              ReverseEstimator(scene, ReverseConfig{{0}, Method::Projective, 1});
            }),
            "reverse mode: method projective is not supported (forward mode only: qsil grad)");
  EXPECT_EQ(message_of([&] { projective_samples_per_index(8, 8, 0.0); }),
            "projective: boundary segments per pixel sample must be in (0, 1024] (got 0.000000)");
  EstimatorConfig c = EstimatorConfig::gradient(params, Method::Projective);
  c.projective_guiding.resolution = 65;
  EXPECT_EQ(message_of([&] { Estimator(scene, c); }), "projective: guiding resolution 65 out of range [0, 64]");
  c.projective_guiding.resolution = 16;
  c.projective_guiding.octree = true;
  EXPECT_EQ(message_of([&] { Estimator(scene, c); }),
            "projective: a guiding resolution and the octree guide exclude each other");
  c.projective_guiding.resolution = 0;
  c.projective_guiding.seeds = 0;
  EXPECT_EQ(message_of([&] { Estimator(scene, c); }),
            "projective: guiding seed paths per pixel 0.000000 out of range (0, 1024]");
  c.projective_guiding.seeds = 64;  // 1024^2 x 64 paths: too many
  const Scene large = load_scene(test::data_file("tests/data/gradient/plane-light.xml"), {{"res", "1024"}});
  EXPECT_EQ(message_of([&] { Estimator(large, c); }),
            "projective: 64 guiding seed paths per pixel at 1024x1024 are 67108864 paths, more than 16777216; lower "
            "--guiding-seeds");
}

}  // namespace
}  // namespace qsil
