// Intersection curves (qsil/edgetree/intersection_curves.h): the broad phase against brute force,
// crossing segments against analytic ones, touching without crossing gives nothing, curves of
// closed meshes close, and each end's Jacobian against finite differences of the construction.
#include "qsil/edgetree/intersection_curves.h"
#include "qsil/edgetree/edge_set.h"
#include "qsil/error.h"
#include "qsil/ray_tracer.h"
#include "qsil/scene.h"
#include "test_data.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <string>
#include <tuple>

namespace qsil::edgetree {
namespace {

TriangleMesh mesh_of(std::vector<Vec3> positions, std::vector<Eigen::Vector3i> triangles) {
  TriangleMesh m;
  m.positions = std::move(positions);
  m.triangles = std::move(triangles);
  return m;
}

TriangleMesh triangle(const Vec3& a, const Vec3& b, const Vec3& c) { return mesh_of({a, b, c}, {{0, 1, 2}}); }

std::vector<CrossingSegment> curves(const std::vector<const TriangleMesh*>& meshes) {
  std::vector<CurveMesh> in;
  for (size_t i = 0; i < meshes.size(); ++i) in.push_back({meshes[i], int(i)});
  return find_intersection_curves(in);
}

/// The icosphere of tests/data/meshes, scaled and moved.
TriangleMesh sphere(double radius, const Vec3& centre) {
  TriangleMesh m = load_obj(test::data_file("tests/data/meshes/icosphere.obj"));
  for (Vec3& p : m.positions) p = centre + radius * p;
  return m;
}

/// A square in the plane y = height, side 2 * half, facing +y (two triangles).
TriangleMesh floor_square(double half, double height = 0) {
  return mesh_of({{-half, height, -half}, {half, height, -half}, {half, height, half}, {-half, height, half}},
                 {{0, 2, 1}, {0, 3, 2}});
}

/// Brute force over all pairs of triangles of `meshes`: those whose boxes lie within `gap` of each
/// other on every axis (gap 0: overlap), sorted as overlapping_triangle_pairs sorts them.
std::vector<TrianglePair> brute_force_pairs(const std::vector<const TriangleMesh*>& meshes, double gap) {
  std::vector<std::pair<int, int>> tris;
  std::vector<Box3> boxes;
  for (int m = 0; m < int(meshes.size()); ++m)
    for (int f = 0; f < meshes[size_t(m)]->num_triangles(); ++f) {
      Box3 box;
      for (int k = 0; k < 3; ++k)
        box.expand(meshes[size_t(m)]->positions[size_t(meshes[size_t(m)]->triangles[size_t(f)][k])]);
      tris.emplace_back(m, f);
      boxes.push_back(box);
    }
  std::vector<TrianglePair> out;
  for (size_t i = 0; i < tris.size(); ++i)
    for (size_t j = i + 1; j < tris.size(); ++j)
      if ((boxes[i].lo.array() <= boxes[j].hi.array() + gap).all() &&
          (boxes[j].lo.array() <= boxes[i].hi.array() + gap).all())
        out.push_back({tris[i].first, tris[i].second, tris[j].first, tris[j].second});
  return out;
}

// ---- The broad phase: every pair of triangles whose boxes overlap, as brute force finds them.
TEST(IntersectionCurves, BroadPhaseFindsEveryOverlappingPairLikeBruteForce) {
  const TriangleMesh a = sphere(0.5, Vec3(0, 0.1, 0)), b = floor_square(1.0);
  TriangleMesh c = load_obj(test::data_file("tests/data/meshes/two-spheres.obj"));
  const std::vector<const TriangleMesh*> meshes{&a, &b, &c};
  const std::vector<TrianglePair> found = overlapping_triangle_pairs(meshes);
  const std::vector<TrianglePair> brute = brute_force_pairs(meshes, 0.0);
  ASSERT_GT(brute.size(), 1000u);
  EXPECT_EQ(found.size(), brute.size());
  EXPECT_TRUE(found == brute) << "the broad phase differs from brute force";
}

// ---- The broad phase with a gap: every pair whose boxes lie within it, as brute force finds them
// (CandidatePairCache fills from it); a test that needs the gap (brute force with none differs).
TEST(IntersectionCurves, BroadPhaseWithAGapFindsEveryPairWithinItLikeBruteForce) {
  const TriangleMesh a = sphere(0.5, Vec3(0, 0.1, 0)), b = floor_square(1.0);
  const std::vector<const TriangleMesh*> meshes{&a, &b};
  const double gap = 0.05;
  const std::vector<TrianglePair> found = overlapping_triangle_pairs(meshes, gap);
  const std::vector<TrianglePair> brute = brute_force_pairs(meshes, gap);
  ASSERT_GT(brute.size(), brute_force_pairs(meshes, 0.0).size() + 100) << "the gap adds too few pairs to test it";
  EXPECT_EQ(found.size(), brute.size());
  EXPECT_TRUE(found == brute) << "the broad phase with a gap differs from brute force";
  EXPECT_THROW(overlapping_triangle_pairs(meshes, -1.0), Error);
}

// ---- Two triangles crossing: the segment is the analytic one.
TEST(IntersectionCurves, CrossingTrianglesGiveTheAnalyticSegment) {
  // A in the plane z = 0; B in the plane x = 0.2, crossing z = 0 along y in [-0.5, 0.5] (its
  // edges from (0.2, +-0.5, -1) to (0.2, 0, 1) meet z = 0 at y = +-0.25).
  const TriangleMesh A = triangle({-1, -1, 0}, {2, -1, 0}, {-1, 2, 0});
  const TriangleMesh B = triangle({0.2, -0.5, -1}, {0.2, 0.5, -1}, {0.2, 0, 1});
  const auto segs = curves({&A, &B});
  ASSERT_EQ(segs.size(), 1u);
  const CrossingSegment& s = segs[0];
  const Vec3 lo(0.2, -0.25, 0), hi(0.2, 0.25, 0);
  const bool forward = (s.p0 - lo).norm() < (s.p0 - hi).norm();
  EXPECT_LT(((forward ? lo : hi) - s.p0).norm(), 1e-15);
  EXPECT_LT(((forward ? hi : lo) - s.p1).norm(), 1e-15);
  EXPECT_EQ(s.shape[0], 0);
  EXPECT_EQ(s.shape[1], 1);
  // Planes: unit outward normals, through the triangles.
  EXPECT_NEAR(s.plane[0].head<3>().dot(Vec3(0, 0, 1)), 1.0, 1e-15);
  EXPECT_NEAR(std::abs(s.plane[1].head<3>().dot(Vec3(1, 0, 0))), 1.0, 1e-15);
  EXPECT_NEAR(s.plane[1].head<3>().dot(Vec3(0.2, 0, 1)) + s.plane[1][3], 0.0, 1e-15);
  // A triangle that crosses the other's plane outside it: no segment.
  const TriangleMesh C = triangle({3.2, -0.5, -1}, {3.2, 0.5, -1}, {3.2, 0, 1});
  EXPECT_TRUE(curves({&A, &C}).empty());
}

// ---- Touching without crossing gives nothing (and no NaN); crossing from a shared vertex does.
TEST(IntersectionCurves, TouchingWithoutCrossingGivesNoSegment) {
  const TriangleMesh A = triangle({-1, 0, -1}, {1, 0, -1}, {0, 0, 1});  // the plane y = 0
  // A vertex in A's plane, inside A, the rest above.
  const TriangleMesh point = triangle({0, 0, 0}, {0.3, 1, 0}, {-0.3, 1, 0.1});
  EXPECT_TRUE(curves({&A, &point}).empty());
  // An edge in A's plane (a triangle standing on A), the rest above.
  const TriangleMesh standing = triangle({-0.2, 0, 0}, {0.2, 0, 0}, {0, 1, 0});
  EXPECT_TRUE(curves({&A, &standing}).empty());
  // Coplanar and overlapping.
  const TriangleMesh coplanar = triangle({-0.5, 0, -0.5}, {0.5, 0, -0.5}, {0, 0, 0.5});
  EXPECT_TRUE(curves({&A, &coplanar}).empty());
  // Two triangles of one mesh sharing an edge, folded through each other's planes.
  const TriangleMesh fold = mesh_of({{0, 0, 0}, {1, 0, 0}, {0.5, 1, 0.3}, {0.5, -0.2, -1}}, {{0, 1, 2}, {1, 0, 3}});
  EXPECT_TRUE(curves({&fold}).empty());
  // Two triangles of one mesh sharing a vertex, each on one side of the other's plane there.
  const TriangleMesh fan =
      mesh_of({{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0.2}, {-1, 1, 0.3}}, {{0, 1, 2}, {0, 3, 4}});
  EXPECT_TRUE(curves({&fan}).empty());
  // A sphere resting on a floor at one vertex (the icosphere's lowest vertex is at -radius).
  const TriangleMesh ball = sphere(0.5, Vec3(0, 0.5, 0)), ground = floor_square(2.0);
  EXPECT_TRUE(curves({&ball, &ground}).empty());
  // A cube resting on the floor: its bottom face coplanar, its sides standing on it.
  TriangleMesh cube = load_obj(test::data_file("scenes/stability/meshes/cube.obj"));
  const Box3 box = cube.bounds();
  for (Vec3& p : cube.positions) p.y() -= box.lo.y();
  EXPECT_TRUE(curves({&cube, &ground}).empty());
}

TEST(IntersectionCurves, TrianglesSharingAVertexCrossFromIt) {
  // Triangle 1 in the plane z = 0; triangle 2 through the shared vertex (0, 0, 0), crossing z = 0
  // along the x axis: its other vertices at z = +-1.
  const TriangleMesh m =
      mesh_of({{0, 0, 0}, {2, -1, 0}, {2, 1, 0}, {2, 0.2, 1}, {2, -0.2, -1}}, {{0, 1, 2}, {0, 3, 4}});
  const auto segs = curves({&m});
  ASSERT_EQ(segs.size(), 1u);
  const Vec3 a = segs[0].p0, b = segs[0].p1;
  const Vec3 shared = a.norm() < b.norm() ? a : b, other = a.norm() < b.norm() ? b : a;
  EXPECT_EQ(shared, Vec3(0, 0, 0));
  EXPECT_NEAR(other.x(), 2.0, 1e-15);  // triangle 2's far edge crosses z = 0 at (2, 0, 0)
  EXPECT_NEAR(other.y(), 0.0, 1e-15);
}

/// Every end of `segs` is shared by exactly two segments (bit for bit): the curves are closed.
void expect_closed(const std::vector<CrossingSegment>& segs) {
  std::map<std::array<double, 3>, int> count;
  for (const CrossingSegment& s : segs)
    for (const Vec3& p : {s.p0, s.p1}) count[{p.x(), p.y(), p.z()}]++;
  int odd = 0;
  for (const auto& [p, n] : count) odd += n != 2;
  EXPECT_EQ(odd, 0) << "of " << count.size() << " ends";
}

// ---- A closed mesh crossing a larger surface, or itself: closed curves; they lie on both.
TEST(IntersectionCurves, CurvesOfClosedMeshesAreClosedAndLieOnBothSurfaces) {
  const TriangleMesh ground = floor_square(2.0);
  // Heights: generic, and 0 (a ring of the icosphere's vertices lies exactly in the floor).
  for (double height : {0.1, 0.0, -0.37}) {
    const TriangleMesh ball = sphere(0.5, Vec3(0, height, 0));
    const auto segs = curves({&ball, &ground});
    ASSERT_GE(segs.size(), 20u) << "height " << height;
    SCOPED_TRACE("height " + std::to_string(height));
    expect_closed(segs);
    double length = 0;
    for (const CrossingSegment& s : segs) {
      EXPECT_LE(std::abs(s.p0.y()), 1e-15);  // on the floor (its plane is y = 0)
      EXPECT_LE(std::abs(s.p1.y()), 1e-15);
      EXPECT_LE(std::hypot(s.p0.x(), s.p0.z()), std::sqrt(0.25 - height * height) + 1e-9);  // inside the circle
      length += (s.p1 - s.p0).norm();
    }
    // The polygon inscribed in the sphere's circle y = 0: a little shorter than the circle.
    const double circle = 2 * kPi * std::sqrt(0.25 - height * height);
    EXPECT_GT(length, 0.97 * circle) << "height " << height;
    EXPECT_LT(length, circle) << "height " << height;
  }
  // Two overlapping spheres in one mesh (radius 0.5 at x = -0.3, 0.45 at x = 0.3): the circle
  // x = 0.0475 / 1.2, y^2 + z^2 = 0.25 - (x + 0.3)^2.
  const TriangleMesh two = load_obj(test::data_file("tests/data/meshes/two-spheres.obj"));
  const auto segs = curves({&two});
  ASSERT_GE(segs.size(), 20u);
  expect_closed(segs);
  for (const CrossingSegment& s : segs) {
    EXPECT_EQ(s.shape[0], 0);
    EXPECT_EQ(s.shape[1], 0);
    for (const Vec3& p : {s.p0, s.p1}) {
      const double x = 0.0475 / 1.2, r = std::sqrt(0.25 - (x + 0.3) * (x + 0.3));
      EXPECT_LT(std::abs(p.x() - x), 0.02);  // near the plane of the circle
      EXPECT_LE(std::hypot(p.y(), p.z()), r + 0.01);
      EXPECT_GT(std::hypot(p.y(), p.z()), r - 0.02);
    }
  }
}

// ---- Each end's Jacobian (CrossingEnd) against central differences of the whole construction.
TEST(IntersectionCurves, EndJacobiansMatchFiniteDifferences) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  int checked = 0;
  for (int trial = 0; trial < 50 && checked < 20; ++trial) {
    TriangleMesh A = triangle({u(rng), u(rng), -0.5}, {u(rng), u(rng), 0.5}, {u(rng), u(rng), u(rng)});
    TriangleMesh B = triangle({u(rng), -0.5, u(rng)}, {u(rng), 0.5, u(rng)}, {u(rng), u(rng), u(rng)});
    const auto segs = curves({&A, &B});
    if (segs.size() != 1) continue;
    ++checked;
    const CrossingSegment& s = segs[0];
    const double h = 1e-6;
    for (int end = 0; end < 2; ++end) {
      const CrossingEnd& e = s.ends[size_t(end)];
      for (int i = 0; i < 5; ++i) {
        const VertexRef r = e.vertices[size_t(i)];
        if (r.shape < 0) continue;
        for (int k = 0; k < 3; ++k) {
          TriangleMesh Ap = A, Am = A, Bp = B, Bm = B;
          (r.shape == 0 ? Ap : Bp).positions[size_t(r.vertex)][k] += h;
          (r.shape == 0 ? Am : Bm).positions[size_t(r.vertex)][k] -= h;
          const auto sp = curves({&Ap, &Bp}), sm = curves({&Am, &Bm});
          ASSERT_EQ(sp.size(), 1u);
          ASSERT_EQ(sm.size(), 1u);
          auto point = [&](const CrossingSegment& c) { return end == 0 ? c.p0 : c.p1; };
          const Vec3 fd = (point(sp[0]) - point(sm[0])) / (2 * h);
          const Vec3 J = e.jacobian.col(3 * i + k);
          EXPECT_LT((fd - J).norm(), 1e-5 * (1 + J.norm())) << "trial " << trial << " end " << end << " vertex " << i;
        }
      }
    }
  }
  EXPECT_GE(checked, 10);
}

// ---- The same segments in the same order for any thread count (the narrow phase runs on
// Embree's threads, in no fixed order).
TEST(IntersectionCurves, SameSegmentsForAnyThreadCount) {
  const TriangleMesh two = load_obj(test::data_file("tests/data/meshes/two-spheres.obj"));
  const TriangleMesh ball = sphere(0.5, Vec3(0.2, 0.1, 0)), ground = floor_square(2.0);
  auto run = [&](int threads) {
    tbb::global_control gc(tbb::global_control::max_allowed_parallelism, size_t(threads));
    return curves({&two, &ball, &ground});
  };
  const auto one = run(1), many = run(2);
  ASSERT_EQ(one.size(), many.size());
  ASSERT_GT(one.size(), 200u);
  for (size_t i = 0; i < one.size(); ++i) {
    EXPECT_EQ(one[i].p0, many[i].p0) << i;
    EXPECT_EQ(one[i].p1, many[i].p1) << i;
    EXPECT_EQ(one[i].face, many[i].face) << i;
    EXPECT_EQ(one[i].ends[0].jacobian, many[i].ends[0].jacobian) << i;
  }
}

// ---- The edge set: segments become always-candidates of a crossing group with its own id.
TEST(IntersectionCurves, EdgeSetKeepsSegmentsAsACrossingGroup) {
  const TriangleMesh ball = sphere(0.5, Vec3(0, 0.1, 0)), ground = floor_square(2.0);
  const std::vector<ForestShapeInput> in{{&ball, 0}, {&ground, 1}};
  const EdgeSet set = EdgeSet::build(in);
  ASSERT_EQ(set.crossing_groups().size(), 1u);
  const CrossingGroup& g = set.crossing_groups()[0];
  EXPECT_EQ(g.id, 2);  // one past the largest shape index
  EXPECT_EQ(g.shape0, 0);
  EXPECT_EQ(g.shape1, 1);
  EXPECT_EQ(g.segments, int(set.crossings().size()));
  int crossing_edges = 0;
  for (const Edge& e : set.always_edges()) {
    if (!e.crossing) continue;
    ++crossing_edges;
    EXPECT_EQ(e.cls, EdgeClass::Intersection);
    EXPECT_EQ(e.shape, g.id);
    EXPECT_TRUE(edge_is_silhouette(e, Vec3(0.3, 2, 0.1)));
    EXPECT_EQ(e.p0, e.crossing->p0);
  }
  EXPECT_EQ(crossing_edges, g.segments);
  EXPECT_GT(set.always_roots().size(), 0u);  // more than 8 segments: a tree of their own
  // Switched off: no segment, and the rest of the set unchanged.
  EdgeSetOptions off;
  off.intersection_curves = false;
  const EdgeSet without = EdgeSet::build(in, off);
  EXPECT_TRUE(without.crossing_groups().empty());
  EXPECT_EQ(without.always_edges().size() + size_t(g.segments), set.always_edges().size());
  EXPECT_EQ(without.edges().size(), set.edges().size());
}

// ---- The refits' pair cache (CandidatePairCache): the same segments and counts as a search
// without it, bit for bit, along a trajectory of small and large moves that makes it serve, fill
// and rest; and a pair that came near only by the two triangles' moving towards each other.
void expect_same_segments(const std::vector<CrossingSegment>& a, const std::vector<CrossingSegment>& b,
                          const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].shape, b[i].shape) << what << " " << i;
    EXPECT_EQ(a[i].face, b[i].face) << what << " " << i;
    EXPECT_EQ(a[i].p0, b[i].p0) << what << " " << i;
    EXPECT_EQ(a[i].p1, b[i].p1) << what << " " << i;
    EXPECT_EQ(a[i].plane[0], b[i].plane[0]) << what << " " << i;
    EXPECT_EQ(a[i].plane[1], b[i].plane[1]) << what << " " << i;
    for (int e = 0; e < 2; ++e) {
      EXPECT_EQ(a[i].ends[size_t(e)].jacobian, b[i].ends[size_t(e)].jacobian) << what << " " << i;
      for (int v = 0; v < 5; ++v) {
        EXPECT_EQ(a[i].ends[size_t(e)].vertices[size_t(v)].shape, b[i].ends[size_t(e)].vertices[size_t(v)].shape);
        EXPECT_EQ(a[i].ends[size_t(e)].vertices[size_t(v)].vertex, b[i].ends[size_t(e)].vertices[size_t(v)].vertex);
      }
    }
  }
}

TEST(IntersectionCurves, PairCacheGivesTheSegmentsOfASearchWithoutIt) {
  TriangleMesh two = load_obj(test::data_file("tests/data/meshes/two-spheres.obj"));
  TriangleMesh ball = sphere(0.5, Vec3(0.2, 0.1, 0)), ground = floor_square(2.0);
  ground.triangles.push_back(ground.triangles[0]);  // a triangle twice: counted, never crossing
  const std::vector<CurveMesh> in{{&two, 0}, {&ball, 1}, {&ground, 2}};
  CandidatePairCache cache;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal;
  int served = 0, searched = 0;
  // Moves per step (scene units): small ones the cache serves, large ones it cannot (the cache
  // rests: kCandidatePairRest), small ones again; then the same counts with other triangles.
  std::vector<double> steps{0, 0.002, 0.002, 0.002, 0.05, 0.002, 0.3, 0.3, 0.3, 0.3};
  steps.resize(steps.size() + kCandidatePairRest + 6, 0.002);
  for (size_t s = 0; s < steps.size(); ++s) {
    // A smooth move of the ball (a sine field) and a rigid one of the two spheres.
    const Vec3 dir = Vec3(normal(rng), normal(rng), normal(rng)).normalized();
    for (Vec3& p : ball.positions) p += steps[s] * std::sin(3.0 * p.dot(dir) + double(s)) * dir;
    for (Vec3& p : two.positions) p += 0.5 * steps[s] * dir;
    IntersectionCurveStats with, without;
    const auto cached = find_intersection_curves(in, &with, &cache);
    const auto plain = find_intersection_curves(in, &without);
    ASSERT_GT(plain.size(), 100u) << s;
    expect_same_segments(cached, plain, "step " + std::to_string(s));
    EXPECT_EQ(with.candidate_pairs, without.candidate_pairs) << s;
    EXPECT_EQ(with.crossing_pairs, without.crossing_pairs) << s;
    (with.from_cache ? served : searched) += 1;
  }
  EXPECT_GE(served, 8);
  EXPECT_GE(searched, 8);
  // Another topology with the same counts (two triangles of the ball swap a vertex), unmoved:
  // the cache must not serve it.
  IntersectionCurveStats before;
  ASSERT_GT(find_intersection_curves(in, &before, &cache).size(), 100u);
  ASSERT_TRUE(before.from_cache && cache.valid);
  std::swap(ball.triangles[0][1], ball.triangles[7][1]);
  IntersectionCurveStats with, without;
  const auto cached = find_intersection_curves(in, &with, &cache);
  expect_same_segments(cached, find_intersection_curves(in, &without), "other topology");
  EXPECT_FALSE(with.from_cache);
  EXPECT_EQ(with.candidate_pairs, without.candidate_pairs);
}

TEST(IntersectionCurves, PairCacheFindsTrianglesThatMovedTowardsEachOther) {
  // A in the plane z = 0 reaching x = 1; B in the plane x = c, across A's plane: they cross where
  // c < 1. The gap g comes from the triangles' edges, not their places.
  auto meshes = [](double shift_a, double c) {
    return std::pair(triangle({shift_a, -1, 0}, {1 + shift_a, -1, 0}, {1 + shift_a, 1, 0}),
                     triangle({c, -2, -1}, {c, 2, -1}, {c, 0, 1}));
  };
  double g = 0;
  {
    auto [a, b] = meshes(0, 5);
    CandidatePairCache probe;
    find_intersection_curves(std::vector<CurveMesh>{{&a, 0}, {&b, 1}}, nullptr, &probe);
    ASSERT_TRUE(probe.valid);
    g = probe.gap;
    ASSERT_GT(g, 0.5);
  }
  // Boxes s g apart: no pair is kept. Then each moves m g towards the other: no vertex moved more
  // than the gap, but the boxes moved 2 m g closer and the triangles cross. (1.2, 0.7): a cache
  // that served for moves up to the whole gap would miss it; (1.0002, 0.5002): one that served
  // a little beyond half the gap.
  for (const auto& [s, m] : {std::pair(1.2, 0.7), std::pair(1.0002, 0.5002)}) {
    auto [a, b] = meshes(0, 1 + s * g);
    const std::vector<CurveMesh> in{{&a, 0}, {&b, 1}};
    CandidatePairCache cache;
    EXPECT_TRUE(find_intersection_curves(in, nullptr, &cache).empty());
    ASSERT_TRUE(cache.valid);
    EXPECT_TRUE(cache.pairs.empty());
    std::tie(a, b) = meshes(m * g, 1 + (s - m) * g);
    const auto plain = find_intersection_curves(in);
    ASSERT_EQ(plain.size(), 1u) << s;
    IntersectionCurveStats stats;
    expect_same_segments(find_intersection_curves(in, &stats, &cache), plain, "moved " + std::to_string(s));
    EXPECT_FALSE(stats.from_cache);
  }
}

// A vertex that is no longer finite makes the cache unusable, whichever coordinate: the search
// runs without it (a cached search would send pairs whose box test a NaN defeats to the narrow
// phase). Two triangles of one mesh share vertex 0 and lie apart in y; after the fill, vertex 0's
// y (and then x, z) becomes NaN. Fails when the check takes the largest move with maxCoeff, which
// passes over a NaN in y or z.
TEST(IntersectionCurves, PairCacheDoesNotServeANonFiniteVertex) {
  for (int axis = 0; axis < 3; ++axis) {
    TriangleMesh m;
    m.positions = {{0, 0, 0}, {1, 0.1, 0}, {1, 0.2, 1}, {-1, 0.3, 0}, {-1, 0.4, 1}};
    m.triangles = {{0, 1, 2}, {0, 3, 4}};
    const std::vector<CurveMesh> in{{&m, 0}};
    CandidatePairCache cache;
    find_intersection_curves(in, nullptr, &cache);
    ASSERT_TRUE(cache.valid);
    m.positions[0][axis] = std::numeric_limits<double>::quiet_NaN();
    IntersectionCurveStats stats;
    find_intersection_curves(in, &stats, &cache);
    EXPECT_FALSE(stats.from_cache) << "axis " << axis;
  }
}

}  // namespace
}  // namespace qsil::edgetree
