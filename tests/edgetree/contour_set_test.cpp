/// @file contour_set_test.cpp
/// The contour set of a narrow lobe (qsil/edgetree/contour_set.h) against brute force over all
/// edges, and the LTC core cone (ltc_core_cone) against quadrature of the LTC density:
/// - on a convex mesh (a subdivided icosphere, 1280 faces) every silhouette edge from p is
///   visible; the set must hold only silhouette edges whose arc comes within the cone (always),
///   and all of them where the cone meets one arc of the silhouette (60 random cones reaching
///   over the outline: at least 55 exactly equal, and every one a subset);
/// - a cone whose walks cannot reach the outline gives an empty set;
/// - on Spot (smooth: its concave edges are creases), random cones through its vertices: sets
///   of silhouette edges in the cone and never a concave one, though concave silhouettes are in
///   the cone in at least 20 of the non-empty cases;
/// - two disjoint spheres in one mesh, the back one's outline hidden behind the front one
///   inside the cone: the set holds the front sphere's silhouette edges only (what the walks
///   reach from the hit on the front sphere), and brute force shows the hidden ones were there;
/// - ltc_core_cone holds at least its mass (less 2 %, for the 16 rim directions standing for
///   the elliptical image) of the LTC distribution over the upper hemisphere, for GGX alpha
///   0.01-0.3 and view angles 0-75 degrees, and the diffuse cone is exact.
/// Fixed seeds.

#include "qsil/edgetree/contour_set.h"
#include "baselines/baseline_test_util.h"
#include "qsil/edgetree/edge_forest.h"
#include "qsil/edgetree/ltc.h"
#include "ray_hits.h"
#include "test_scenes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <utility>

namespace qsil::edgetree {
namespace {

/// The probe of a circular cone with axis `axis` and half-angle `beta` from p (its core is the
/// cone itself): its axis ray's hit.
ContourProbe probe_of(const TriangleMesh& m, const Vec3& p, const Vec3& axis, double beta) {
  ContourProbe probe;
  probe.axis = axis.normalized();
  probe.cos_half_angle = std::cos(beta);
  // A circular core: the rotation taking the axis to z, and the cone's own angle.
  const Vec3 t = probe.axis.unitOrthogonal(), b = probe.axis.cross(t);
  probe.to_cosine << t.transpose(), b.transpose(), probe.axis.transpose();
  probe.cos_core = probe.cos_half_angle;
  if (const auto hit = test::ray_hits_mesh(p, probe.axis, m)) {
    probe.hits[0] = {0, hit->face, Vec3(p + hit->t * probe.axis), probe.axis};
    probe.count = 1;
  }
  return probe;
}

/// Brute force: every edge of the forest (tree and always-candidate) that is a silhouette from p
/// and whose arc from p comes within the cone; concave ones only with `concave`.
std::set<const Edge*> brute_force(const EdgeForest& forest, const Vec3& p, const ContourProbe& probe,
                                        bool concave = false) {
  std::set<const Edge*> out;
  for (const auto* arr : {&forest.edges(), &forest.always_edges()})
    for (const Edge& e : *arr)
      if ((concave || e.cls != EdgeClass::Concave) && edge_is_silhouette(e, p) &&
          arc_max_cos(e.p0, e.p1, p, probe.axis) >= probe.cos_half_angle)
        out.insert(&e);
  return out;
}

std::set<const Edge*> contour(const ContourIndex& index, const Vec3& p, const ContourProbe& probe) {
  std::vector<const Edge*> v;
  index.contour_edges(probe, p, nullptr, v);
  const std::set<const Edge*> s(v.begin(), v.end());
  EXPECT_EQ(s.size(), v.size()) << "an edge listed twice";
  return s;
}

TEST(ContourSet, ConvexMeshGivesTheSilhouetteEdgesInTheCone) {
  const std::vector<TriangleMesh> meshes{test::icosphere(3)};
  const EdgeForest forest = baselines_test::forest_over(meshes);
  const std::vector<ForestShapeInput> in{{&meshes[0], 0}};
  const ContourIndex index = ContourIndex::build(in, forest);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  int equal = 0, nonempty = 0;
  const int n = 60;
  for (int i = 0; i < n; ++i) {
    // p at distance 3-6 from the centre; the axis at 80-98 % of the outline's angle from the
    // centre's direction, so that it meets the sphere near its outline, and a cone 1.2-3 times
    // as wide as the axis is from the outline, so that it reaches over it.
    const Vec3 dir = Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5).normalized();
    const double dist = 3 + 3 * u(rng);
    const Vec3 p = dist * dir;
    const double outline = std::asin(1.0 / dist);
    const double angle = outline * (0.8 + 0.18 * u(rng));
    const Vec3 side = (-dir).unitOrthogonal();
    const double phi = 2 * kPi * u(rng);
    const Vec3 across = std::cos(phi) * side + std::sin(phi) * (-dir).cross(side);
    const Vec3 axis = std::cos(angle) * (-dir) + std::sin(angle) * across;
    const double beta = (outline - angle) * (1.2 + 1.8 * u(rng));
    const ContourProbe probe = probe_of(meshes[0], p, axis, beta);
    ASSERT_EQ(probe.count, 1) << "case " << i << ": the axis must meet the sphere";
    const std::set<const Edge*> got = contour(index, p, probe), want = brute_force(forest, p, probe);
    for (const Edge* e : got) EXPECT_TRUE(want.count(e)) << "case " << i << ": not a silhouette in the cone";
    equal += got == want;
    nonempty += !want.empty();
  }
  std::printf("[ measured ] %d of %d cones gave exactly the brute-force set (%d non-empty)\n", equal, n, nonempty);
  EXPECT_GE(equal, 55);
  EXPECT_EQ(nonempty, n) << "every cone must reach the outline for the test to have power";
}

TEST(ContourSet, ConeAwayFromTheOutlineGivesNothing) {
  const std::vector<TriangleMesh> meshes{test::icosphere(3)};
  const EdgeForest forest = baselines_test::forest_over(meshes);
  const std::vector<ForestShapeInput> in{{&meshes[0], 0}};
  const ContourIndex index = ContourIndex::build(in, forest);
  const Vec3 p(0, 0, 4);
  const ContourProbe probe = probe_of(meshes[0], p, Vec3(0, 0, -1), 0.05);  // at the centre, outline 0.25 rad away
  ASSERT_EQ(probe.count, 1);
  EXPECT_TRUE(brute_force(forest, p, probe).empty());
  EXPECT_TRUE(contour(index, p, probe).empty());
  // No hit, no set.
  ContourProbe none = probe;
  none.count = 0;
  EXPECT_TRUE(contour(index, p, none).empty());
}

TEST(ContourSet, HiddenOutlineBehindTheHitSurfaceIsLeftOut) {
  // One mesh, two disjoint spheres: the front one at the origin, the back one behind it and to
  // the side, so that from p the back sphere's outline passes behind the front sphere.
  TriangleMesh both = test::icosphere(3);
  const TriangleMesh back = test::icosphere(3, Vec3(0.9, 0, -4), 1.0);
  const int offset = both.num_vertices();
  for (const Vec3& x : back.positions) both.positions.push_back(x);
  for (const auto& t : back.triangles) both.triangles.push_back(t + Eigen::Vector3i::Constant(offset));
  both.normals = vertex_normals(both);
  const std::vector<TriangleMesh> meshes{both};
  const EdgeForest forest = baselines_test::forest_over(meshes);
  const std::vector<ForestShapeInput> in{{&meshes[0], 0}};
  const ContourIndex index = ContourIndex::build(in, forest);
  const Vec3 p(0, 0, 5);
  // The axis meets the front sphere near its right outline (x > 0), where the back sphere's
  // left outline lies behind it.
  const Vec3 axis = (Vec3(0.75, 0, 0) - p).normalized();
  const ContourProbe probe = probe_of(meshes[0], p, axis, 0.12);
  ASSERT_EQ(probe.count, 1);
  ASSERT_GT(probe.hits[0].point.z(), -2.0) << "the axis must meet the front sphere";
  const std::set<const Edge*> got = contour(index, p, probe), want = brute_force(forest, p, probe);
  int hidden = 0, front = 0;
  for (const Edge* e : want) (e->v0 >= offset ? hidden : front)++;
  ASSERT_GT(hidden, 0) << "the back sphere's outline must be inside the cone for the test to have power";
  ASSERT_GT(front, 0);
  int got_front = 0;
  for (const Edge* e : got) {
    EXPECT_LT(e->v0, offset) << "an edge of the hidden back sphere";
    EXPECT_TRUE(want.count(e));
    ++got_front;
  }
  EXPECT_EQ(got_front, front) << "every front silhouette edge in the cone";
}

/// A random cone of half-angle 0.1 on `mesh`: from p 1.5-3 diagonals from the centre of its box,
/// the axis toward a random vertex (with its probe; count 0 where the axis misses the mesh).
std::pair<Vec3, ContourProbe> random_probe(const TriangleMesh& mesh, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  const Box3 box = mesh.bounds();
  const Vec3 dir = Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5).normalized();
  const Vec3 p = box.center() + (1.5 + 1.5 * u(rng)) * box.diagonal() * dir;
  const Vec3 target = mesh.positions[size_t(u(rng) * mesh.num_vertices()) % mesh.positions.size()];
  return {p, probe_of(mesh, p, target - p, 0.1)};
}

TEST(ContourSet, SpotSetsHoldSilhouettesInTheConeButNoConcaveEdge) {
  // Spot smooth-shaded: its concave edges are creases (always-candidates), and where a valley's
  // faces face p differently the edge is a silhouette of no visible outline.
  std::vector<TriangleMesh> meshes{baselines_test::test_mesh("spot.obj")};
  std::vector<ForestShapeInput> in{{&meshes[0], 0, false, CreaseSet::Concave}};
  const EdgeForest forest = EdgeForest::build(in);
  const ContourIndex index = ContourIndex::build(in, forest);
  std::mt19937_64 rng(3);
  int nonempty = 0, with_concave = 0;
  for (int i = 0; i < 200; ++i) {
    const auto [p, probe] = random_probe(meshes[0], rng);
    if (probe.count == 0) continue;
    const std::set<const Edge*> got = contour(index, p, probe), want = brute_force(forest, p, probe);
    for (const Edge* e : got) {
      EXPECT_NE(e->cls, EdgeClass::Concave) << "case " << i;
      EXPECT_TRUE(want.count(e)) << "case " << i << ": not a silhouette in the cone";
    }
    nonempty += !got.empty();
    with_concave += !got.empty() && brute_force(forest, p, probe, true).size() > want.size();
  }
  std::printf("[ measured ] %d non-empty sets, %d of them with concave silhouettes in the cone\n", nonempty,
              with_concave);
  EXPECT_GE(with_concave, 20) << "concave silhouettes must be in reach for the test to have power";
}

/// The (v0, v1) pairs of a set of edges: the same edges across two forests.
std::set<std::pair<int, int>> keys(const std::set<const Edge*>& edges) {
  std::set<std::pair<int, int>> out;
  for (const Edge* e : edges) out.insert({e->v0, e->v1});
  return out;
}

TEST(ContourSet, RefitIndexGivesTheSetsOfANewBuild) {
  // Spot moved by a smooth displacement (some convex edges turn concave): the index refitted with
  // its refitted forest (ContourIndex::refit, EdgeForest::refit) gives, for 200 random cones, the
  // same edges as an index built anew on a forest built anew. Fails when the refit leaves the
  // edges' planes, classes or links as they were.
  std::vector<TriangleMesh> meshes{baselines_test::test_mesh("spot.obj")};
  std::vector<ForestShapeInput> in{{&meshes[0], 0, false, CreaseSet::Concave}};
  EdgeForest forest = EdgeForest::build(in);
  ContourIndex index = ContourIndex::build(in, forest);
  const double d = meshes[0].bounds().diagonal();
  for (Vec3& x : meshes[0].positions) x += 0.01 * d * Vec3(std::sin(9 * x.y() / d), std::cos(7 * x.z() / d), 0.0);
  const RefitReport r = forest.refit(in);
  ASSERT_TRUE(r.refitted) << r.reason;
  EXPECT_GT(r.retired, 0) << "the displacement should turn convex edges concave";
  ASSERT_TRUE(index.refit(in, forest));
  const EdgeForest new_forest = EdgeForest::build(in);
  const ContourIndex new_index = ContourIndex::build(in, new_forest);
  std::mt19937_64 rng(5);
  int nonempty = 0;
  for (int i = 0; i < 200; ++i) {
    const auto [p, probe] = random_probe(meshes[0], rng);
    if (probe.count == 0) continue;
    const auto got = keys(contour(index, p, probe)), want = keys(contour(new_index, p, probe));
    EXPECT_EQ(got, want) << "case " << i;
    nonempty += !want.empty();
  }
  EXPECT_GE(nonempty, 50);
  // Another mesh than the one indexed: refused.
  std::vector<TriangleMesh> other{meshes[0]};
  other[0].triangles.pop_back();
  std::vector<ForestShapeInput> in_other{{&other[0], 0, false, CreaseSet::Concave}};
  EXPECT_FALSE(index.refit(in_other, forest));
}

/// Integral of the LTC density over the directions within angle `half` of `axis`, by a midpoint
/// rule in (s, phi) with theta = half s^2 (fine near the axis, where the lobe is).
double mass_within(const LTC& ltc, const Vec3& axis, double half) {
  const Vec3 a = axis.normalized(), t = a.unitOrthogonal(), b = a.cross(t);
  const int ns = 2000, np = 512;
  double sum = 0;
  for (int i = 0; i < ns; ++i) {
    const double sv = (i + 0.5) / ns, th = half * sv * sv, dth = 2 * half * sv / ns;
    for (int j = 0; j < np; ++j) {
      const double ph = (j + 0.5) / np * 2 * kPi;
      const Vec3 w = std::cos(th) * a + std::sin(th) * (std::cos(ph) * t + std::sin(ph) * b);
      sum += ltc_eval(ltc, w) * std::sin(th) * dth * (2 * kPi / np);
    }
  }
  return sum;
}

TEST(LTCCoreCone, HoldsItsMass) {
  // The clamped cosine: the cone is the rim itself.
  const LTCCone diffuse = ltc_core_cone(ltc_diffuse(), 0.75);
  EXPECT_NEAR(diffuse.axis.z(), 1.0, 1e-12);
  EXPECT_NEAR(diffuse.cos_half_angle, 0.5, 1e-12);
  double worst = 1;
  for (double alpha : {0.01, 0.03, 0.1, 0.3})
    for (double theta_o : {0.0, 0.5, 1.0, 1.3}) {
      const LTC ltc = ltc_ggx(alpha, Vec3(std::sin(theta_o), 0, std::cos(theta_o)));
      for (double mass : {0.9, kContourConeMass}) {
        const LTCCone cone = ltc_core_cone(ltc, mass);
        // The total over the sphere (ltc_eval is 0 below the horizon: what it leaves of the lobe).
        const double total = mass_within(ltc, cone.axis, kPi);
        const double in = mass_within(ltc, cone.axis, std::acos(std::clamp(cone.cos_half_angle, -1.0, 1.0)));
        worst = std::min(worst, in / total - mass);
        EXPECT_GE(in / total, mass - 0.02) << "alpha " << alpha << " theta_o " << theta_o << " mass " << mass;
      }
    }
  std::printf("[ measured ] smallest (inside share - mass): %.4f\n", worst);
}

}  // namespace
}  // namespace qsil::edgetree
