/// @file forest_soundness_test.cpp
/// Soundness of the rejection test by brute force (docs/architecture.md §5, §9): for every inner node of
/// the forests of spot, torus, bunny and a subdivided cube, and many shading points (uniform in a
/// box 3x the mesh's size, very close to the surface, exactly on triangle planes), whenever a
/// node's patch has a silhouette edge (edge_is_silhouette, double, world frame) the test must
/// accept: zero false rejects, in quadric and box modes. Ground truth is computed bottom-up (a
/// node has a silhouette iff a child does; leaves exactly). Also degenerate meshes (translated by
/// 1e4, scaled by 1e-4, near-planar open sheet) and degenerate patches fitted directly (planar,
/// single wedge, nearly parallel planes). Fixed seeds. The quick suite uses 1e4 points per mesh,
/// the Slow suite 1e5.

#include "qsil/edgetree/edge_forest.h"
#include "qsil/edgetree/node_fit.h"
#include "qsil/edgetree/node_rejection.h"
#include "qsil/scene.h"

#include <gtest/gtest.h>

#include <tbb/parallel_for.h>
#include "soundness_set.h"
#include "test_data.h"

#include <atomic>
#include <cmath>
#include <map>
#include <tuple>
#include <utility>
#include <vector>
#include <random>
#include <string>

namespace qsil::edgetree {
namespace {

using test::make_cube;
using test::shading_points;

// ---- test meshes

// An open, gently curved sheet z = c (x^2 + y^2) (a dome for c < 0: convex edges) over [-1,1]^2 (n x n quads): bend
// angles ~ 4c/n, above the flat threshold; boundary edges go to the always list.
TriangleMesh make_sheet(int n, double c) {
  TriangleMesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double x = -1 + 2.0 * i / n, y = -1 + 2.0 * j / n;
      m.positions.emplace_back(x, y, c * (x * x + y * y));
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, cc = a + n + 2, d = a + n + 1;
      m.triangles.push_back(Eigen::Vector3i(a, b, cc));
      m.triangles.push_back(Eigen::Vector3i(a, cc, d));
    }
  return m;
}

TriangleMesh transformed(TriangleMesh m, double scale, const Vec3& offset) {
  for (auto& p : m.positions) p = p * scale + offset;
  return m;
}

// ---- soundness check (shading points: tests/soundness_set.h)

struct SoundnessResult {
  long long tests = 0;  // (inner node, point) pairs with a silhouette
  long long false_rejects_quadric = 0;
  long long false_rejects_box = 0;
  long long accepts_no_sil_quadric = 0, accepts_no_sil_box = 0, no_sil = 0;
};

// For every point: ground truth per node bottom-up, then the rejection test of every inner node.
SoundnessResult check_forest(const EdgeForest& f, const std::vector<Vec3>& pts) {
  std::atomic<long long> tests{0}, frq{0}, frb{0}, aq{0}, ab{0}, ns{0};
  const int N = int(f.nodes().size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pts.size(), 64), [&](const auto& r) {
    std::vector<char> has(N);
    long long lt = 0, lq = 0, lb = 0, laq = 0, lab = 0, lns = 0;
    for (size_t k = r.begin(); k != r.end(); ++k) {
      const Vec3& p = pts[k];
      for (int i = N - 1; i >= 0; --i) {  // children have larger indices than their parents
        const ForestNode& n = f.node(i);
        if (n.is_leaf()) {
          has[i] = leaf_has_silhouette(f, i, p);
        } else {
          bool h = false;
          for (int c = n.first; c < n.first + n.count; ++c) h = h || has[c];
          has[i] = h;
          const bool q = may_have_silhouette(f, i, p, NodeTest::DualBoxAndQuadrics);
          const bool b = may_have_silhouette(f, i, p, NodeTest::DualBox);
          if (h) {
            ++lt;
            lq += !q;
            lb += !b;
          } else {
            ++lns;
            laq += q;
            lab += b;
          }
        }
      }
    }
    tests += lt;
    frq += lq;
    frb += lb;
    aq += laq;
    ab += lab;
    ns += lns;
  });
  return {tests.load(), frq.load(), frb.load(), aq.load(), ab.load(), ns.load()};
}

void expect_sound(const TriangleMesh& mesh, int npoints, unsigned seed, const std::string& name,
                  bool keep_concave = false) {
  ForestShapeInput in{&mesh, 0};
  ForestOptions opt;
  opt.edges.keep_concave = keep_concave;
  const EdgeForest f = EdgeForest::build(std::span(&in, 1), opt);
  ASSERT_GT(f.stats()[0].inner_nodes, 0) << name;
  const SoundnessResult r = check_forest(f, shading_points(mesh, npoints, seed));
  EXPECT_GT(r.tests, 0) << name;
  EXPECT_EQ(r.false_rejects_quadric, 0) << name << " quadric, of " << r.tests;
  EXPECT_EQ(r.false_rejects_box, 0) << name << " box, of " << r.tests;
  // Not a soundness property, but a smoke check that the test rejects something at all.
  EXPECT_LT(r.accepts_no_sil_quadric, r.no_sil) << name;
  std::printf(
      "[%s] %lld (node, point) pairs with a silhouette, false rejects quadric %lld box "
      "%lld; false-accept rate quadric %.3f box %.3f\n",
      name.c_str(), r.tests, r.false_rejects_quadric, r.false_rejects_box,
      r.no_sil ? double(r.accepts_no_sil_quadric) / r.no_sil : 0.0,
      r.no_sil ? double(r.accepts_no_sil_box) / r.no_sil : 0.0);
}

// A test mesh by file name (test_data.h: a missing file fails the test with its path).
TriangleMesh mesh_file(const char* name) { return load_obj(test::mesh_file(name)); }

// ---- quick suite (1e4 points per mesh)

TEST(ForestSoundness, Spot) { expect_sound(mesh_file("spot.obj"), 10000, 1, "spot"); }
TEST(ForestSoundness, TorusKeepConcave) { expect_sound(mesh_file("torus.obj"), 10000, 2, "torus+concave", true); }
TEST(ForestSoundness, Cube) { expect_sound(make_cube(8), 10000, 3, "cube"); }
TEST(ForestSoundness, SpotTranslated1e4) {
  expect_sound(transformed(mesh_file("spot.obj"), 1.0, Vec3(1e4, -1e4, 1e4)), 10000, 4, "spot+1e4");
}
TEST(ForestSoundness, SpotScaled1em4) {
  expect_sound(transformed(mesh_file("spot.obj"), 1e-4, Vec3(0.3e-4, 0, 0)), 10000, 5, "spot*1e-4");
}
TEST(ForestSoundness, NearPlanarSheet) { expect_sound(make_sheet(24, -0.01), 10000, 6, "sheet"); }

// ---- slow suite (1e5 points per mesh)

TEST(SlowForestSoundness, Spot) { expect_sound(mesh_file("spot.obj"), 100000, 11, "spot"); }
TEST(SlowForestSoundness, Torus) { expect_sound(mesh_file("torus.obj"), 100000, 12, "torus"); }
TEST(SlowForestSoundness, Bunny) { expect_sound(mesh_file("bunny.obj"), 100000, 13, "bunny"); }
TEST(SlowForestSoundness, Cube) { expect_sound(make_cube(8), 100000, 14, "cube"); }
TEST(SlowForestSoundness, Degenerate) {
  expect_sound(transformed(mesh_file("torus.obj"), 1.0, Vec3(1e4, 1e4, -1e4)), 100000, 15, "torus+1e4");
  expect_sound(transformed(mesh_file("bunny.obj"), 1e-4, Vec3::Zero()), 100000, 16, "bunny*1e-4");
  expect_sound(make_sheet(40, -0.003), 100000, 17, "sheet");
}

// ---- refit forests (EdgeForest::refit) after the vertices moved

// `mesh` with every vertex moved by an isotropic Gaussian of standard deviation sigma times the
// bounding-box diagonal (fixed seed).
TriangleMesh jittered(TriangleMesh m, double sigma, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, sigma * m.bounds().diagonal());
  for (auto& p : m.positions) p += Vec3(g(rng), g(rng), g(rng));
  return m;
}

// A smooth displacement: every vertex pushed along x by amp * diagonal * sin(3 y / diagonal).
TriangleMesh swirled(TriangleMesh m, double amp) {
  const double d = m.bounds().diagonal();
  for (auto& p : m.positions) p.x() += amp * d * std::sin(3.0 * p.y() / d);
  return m;
}

// Builds the forest of `before` (smooth shading: its concave edges are creases), moves the
// vertices to those of `after` in place and refits. `mesh` holds `after` on return.
EdgeForest refit_forest(const TriangleMesh& before, const TriangleMesh& after, TriangleMesh& mesh, RefitReport* report,
                        CreaseSet creases = CreaseSet::Concave) {
  mesh = before;
  ForestShapeInput in{&mesh, 0, false, creases};
  EdgeForest f = EdgeForest::build(std::span(&in, 1));
  mesh.positions = after.positions;
  const RefitReport r = f.refit(std::span(&in, 1));
  EXPECT_TRUE(r.refitted) << r.reason;
  if (report) *report = r;
  return f;
}

// The rejection test of a refit forest is sound: zero false rejects over the soundness set of
// the moved mesh, in quadric and box modes, for jitter of 1e-3 and 1e-2 of the diagonal (the
// latter flips many edges between convex and concave) and a smooth displacement.
void expect_refit_sound(const TriangleMesh& mesh0, unsigned seed, const std::string& name) {
  for (const auto& [label, moved] :
       {std::pair<std::string, TriangleMesh>{"jitter 1e-3", jittered(mesh0, 1e-3, seed)},
        {"jitter 1e-2", jittered(mesh0, 1e-2, seed + 1)},
        {"swirl 0.05", swirled(mesh0, 0.05)}}) {
    TriangleMesh mesh;
    RefitReport rep;
    const EdgeForest f = refit_forest(mesh0, moved, mesh, &rep);
    const SoundnessResult r = check_forest(f, shading_points(mesh, 4000, seed));
    EXPECT_GT(r.tests, 0) << name << " " << label;
    EXPECT_EQ(r.false_rejects_quadric, 0) << name << " " << label << " quadric, of " << r.tests;
    EXPECT_EQ(r.false_rejects_box, 0) << name << " " << label << " box, of " << r.tests;
    EXPECT_GT(rep.bounds, 0) << name << " " << label;
    std::printf("[%s, %s] refit: %d bounds (%d anew, %d box-only), %d retired, %d unflattened, box growth %.3f; "
                "false-accept rate quadric %.3f\n",
                name.c_str(), label.c_str(), rep.bounds, rep.refitted_fully, rep.box_only, rep.retired,
                rep.unflattened, rep.box_growth, r.no_sil ? double(r.accepts_no_sil_quadric) / r.no_sil : 0.0);
  }
}

TEST(ForestRefitSoundness, Spot) { expect_refit_sound(mesh_file("spot.obj"), 21, "spot"); }
TEST(ForestRefitSoundness, Cube) { expect_refit_sound(make_cube(8), 22, "cube"); }
TEST(ForestRefitSoundness, Sheet) { expect_refit_sound(make_sheet(24, -0.01), 23, "sheet"); }

// An edge's identity across forests: shape and vertex pair.
std::tuple<int, int, int> edge_key(const Edge& e) { return {e.shape, e.v0, e.v1}; }

// Per point, the mesh edges that are discontinuities (is_discontinuity) in the edge arrays of `f`,
// counted with multiplicity (a tree edge and its crease copy both counting would be a double count).
// The segments of intersection curves are no mesh edges (NoMotionAndCrossings checks those).
std::map<std::tuple<int, int, int>, int> discontinuities(const EdgeForest& f, const Vec3& p) {
  std::map<std::tuple<int, int, int>, int> out;
  for (const auto* arr : {&f.edges(), &f.always_edges()})
    for (const Edge& e : *arr)
      if (!e.crossing && is_discontinuity(e, p)) ++out[edge_key(e)];
  return out;
}

// What a refit holds as discontinuities is what a forest built anew on the moved mesh holds, each
// edge once: no edge lost when it flips between convex and concave or stops being flat, none
// counted twice (a retired tree edge and its crease copy). With the soundness of the rejection
// test above, every discontinuity stays reachable. Fails if retiring, promoting or unflattening
// is left out (checked by breaking each); also where concave edges are culled (CreaseSet::None)
// and some turn convex.
TEST(ForestRefit, SameDiscontinuitiesAsARebuild) {
  for (const auto& [name, mesh0, creases] :
       {std::tuple<std::string, TriangleMesh, CreaseSet>{"spot", mesh_file("spot.obj"), CreaseSet::Concave},
        {"cube", make_cube(6), CreaseSet::Concave},
        {"spot, concave edges culled", mesh_file("spot.obj"), CreaseSet::None}}) {
    const TriangleMesh moved = jittered(mesh0, 1e-2, 31);
    TriangleMesh mesh;
    RefitReport rep;
    const EdgeForest refit = refit_forest(mesh0, moved, mesh, &rep, creases);
    ForestShapeInput in{&mesh, 0, false, creases};
    const EdgeForest rebuilt = EdgeForest::build(std::span(&in, 1));
    if (name == "spot") {
      EXPECT_GT(rep.retired, 0) << name << ": the jitter should flip convex edges to concave";
    } else {
      EXPECT_GT(rep.unflattened, 0) << name << ": the jitter should bend flat edges or turn culled ones convex";
    }
    EXPECT_TRUE(rep.rebuild_advised()) << name << ": a jitter of 1e-2 of the diagonal leaves a loose forest";
    int checked = 0;
    for (const Vec3& p : shading_points(mesh, 300, 32)) {
      const auto a = discontinuities(refit, p), b = discontinuities(rebuilt, p);
      for (const auto& [key, count] : a) ASSERT_EQ(count, 1) << name << ": an edge counted twice";
      // A refit keeps a crease that became convex (a conservative extra candidate), so the
      // refit's set may be larger; the rebuilt one's must be in it.
      for (const auto& [key, count] : b) {
        ASSERT_TRUE(a.count(key)) << name << ": edge (" << std::get<1>(key) << ", " << std::get<2>(key)
                                  << ") is a discontinuity after a rebuild, not after the refit";
        ++checked;
      }
    }
    EXPECT_GT(checked, 1000) << name;
  }
}

// A refit with the vertices where they were changes no bound beyond rounding, retires nothing
// and finds the same intersection curves; moving one of two cubes into the other makes the refit
// find their crossing, as a rebuild does.
TEST(ForestRefit, NoMotionAndCrossings) {
  TriangleMesh a = make_cube(4), b = transformed(make_cube(4), 1.0, Vec3(3, 0.3, 0.2));
  std::vector<ForestShapeInput> in{{&a, 0, false, CreaseSet::Concave}, {&b, 1, false, CreaseSet::Concave}};
  EdgeForest f = EdgeForest::build(in);
  const std::vector<NodeBound> before = f.bounds();
  RefitReport r = f.refit(in);
  ASSERT_TRUE(r.refitted) << r.reason;
  EXPECT_EQ(r.retired, 0);
  EXPECT_EQ(r.unflattened, 0);
  EXPECT_EQ(r.refitted_fully, 0);
  EXPECT_NEAR(r.box_growth, 1.0, 1e-9);
  EXPECT_FALSE(r.rebuild_advised());
  for (size_t i = 0; i < before.size(); ++i) {
    EXPECT_LT((f.bounds()[i].bq_hi - before[i].bq_hi).cwiseAbs().maxCoeff(), 1e-6) << "bound " << i;
    EXPECT_LT((f.bounds()[i].bq_lo - before[i].bq_lo).cwiseAbs().maxCoeff(), 1e-6) << "bound " << i;
  }
  EXPECT_TRUE(f.crossing_groups().empty());
  for (auto& p : b.positions) p.x() -= 1.5;  // now overlapping a
  r = f.refit(in);
  ASSERT_TRUE(r.refitted) << r.reason;
  const EdgeForest rebuilt = EdgeForest::build(in);
  ASSERT_EQ(rebuilt.crossing_groups().size(), 1u);
  ASSERT_EQ(f.crossing_groups().size(), 1u);
  EXPECT_EQ(f.crossing_groups()[0].segments, rebuilt.crossing_groups()[0].segments);
  EXPECT_EQ(f.always_edges().size(), rebuilt.always_edges().size());
}

// A refit of unmoved vertices gives every node the B_p and L_w it was built with, to the bit: build
// and refit both take an inner node's from its children, in the same order (the build once summed
// L_w over all of a node's edges, which rounds differently: then this fails at the root's L_w;
// B_p, a min and max, cannot tell the two apart). Edge lengths come out equal because build
// (mesh_edges.cpp) and refit (edge_set.cpp) compute them with the same expression. Spot, whose
// concave creases make an always-candidate tree as well.
TEST(ForestRefit, UnmovedRefitKeepsTheBuiltExtents) {
  const TriangleMesh mesh = mesh_file("spot.obj");
  ForestShapeInput in{&mesh, 0, false, CreaseSet::Concave};
  EdgeForest f = EdgeForest::build(std::span(&in, 1));
  const std::vector<ForestNode> built = f.nodes();
  ASSERT_TRUE(f.refit(std::span(&in, 1)).refitted);
  ASSERT_EQ(f.nodes().size(), built.size());
  int always = 0;
  for (size_t i = 0; i < built.size(); ++i) {
    const ForestNode &n = f.nodes()[i], &m = built[i];
    ASSERT_TRUE(n.bp.lo == m.bp.lo && n.bp.hi == m.bp.hi) << "node " << i;
    ASSERT_EQ(n.lw, m.lw) << "node " << i;
    ASSERT_EQ(n.lw_smooth, m.lw_smooth) << "node " << i;
    always += n.always();
  }
  EXPECT_GT(always, 100);
}

// A refit after a small move takes its curves' pairs from the pair cache its first refit filled
// (CandidatePairCache), and its crossing segments are those of a forest built at the new places.
TEST(ForestRefit, CurvesFromThePairCacheAreThoseOfABuild) {
  TriangleMesh a = make_cube(4), b = transformed(make_cube(4), 1.0, Vec3(1.5, 0.3, 0.2));
  std::vector<ForestShapeInput> in{{&a, 0, false, CreaseSet::Concave}, {&b, 1, false, CreaseSet::Concave}};
  EdgeForest f = EdgeForest::build(in);
  ASSERT_TRUE(f.refit(in).refitted);  // fills the cache
  EXPECT_FALSE(f.crossing_stats().from_cache);
  for (int step = 1; step <= 3; ++step) {
    for (Vec3& p : b.positions) p += 1e-3 * Vec3(std::sin(3 * p.y() + step), std::cos(2 * p.z()), 0.5);
    ASSERT_TRUE(f.refit(in).refitted);
    EXPECT_TRUE(f.crossing_stats().from_cache) << step;
    const EdgeForest built = EdgeForest::build(in);
    EXPECT_EQ(f.crossing_stats().candidate_pairs, built.crossing_stats().candidate_pairs) << step;
    std::vector<const Edge*> mine, theirs;
    for (const Edge& e : f.always_edges())
      if (e.crossing) mine.push_back(&e);
    for (const Edge& e : built.always_edges())
      if (e.crossing) theirs.push_back(&e);
    ASSERT_GT(mine.size(), 8u);
    ASSERT_EQ(mine.size(), theirs.size()) << step;
    for (size_t i = 0; i < mine.size(); ++i) {
      EXPECT_EQ(mine[i]->p0, theirs[i]->p0) << step << " " << i;
      EXPECT_EQ(mine[i]->p1, theirs[i]->p1) << step << " " << i;
      EXPECT_EQ(mine[i]->crossing->ends[0].jacobian, theirs[i]->crossing->ends[0].jacobian) << step << " " << i;
    }
  }
}

// A refit refuses what is not a move of the vertices built, changing nothing.
TEST(ForestRefit, RefusesOtherTopology) {
  TriangleMesh a = make_cube(4);
  ForestShapeInput in{&a, 0, false, CreaseSet::Concave};
  EdgeForest f = EdgeForest::build(std::span(&in, 1));
  const size_t edges = f.edges().size();
  std::swap(a.triangles[0][1], a.triangles[0][2]);
  RefitReport r = f.refit(std::span(&in, 1));
  EXPECT_FALSE(r.refitted);
  EXPECT_NE(r.reason.find("shape 0: its triangles changed"), std::string::npos) << r.reason;
  EXPECT_EQ(f.edges().size(), edges);
  std::swap(a.triangles[0][1], a.triangles[0][2]);
  in.creases = CreaseSet::All;
  r = f.refit(std::span(&in, 1));
  EXPECT_FALSE(r.refitted);
  EXPECT_NE(r.reason.find("crease rule"), std::string::npos) << r.reason;
  in.creases = CreaseSet::Concave;
  EXPECT_FALSE(f.refit({}).refitted);
  EXPECT_TRUE(f.refit({}).rebuild_advised());
  EXPECT_TRUE(f.refit(std::span(&in, 1)).refitted);
}

// ---- degenerate patches fitted directly

Vec4 plane_of(const Vec3& n, const Vec3& x0) {
  const Vec3 u = n.normalized();
  return Vec4(u.x(), u.y(), u.z(), -u.dot(x0));
}

// Checks bound_may_have_silhouette against the wedge predicate for points near the wedges.
void expect_bound_sound(const NodeFit& fit, const std::vector<Wedge>& wedges, double size, const Vec3& center,
                        unsigned seed, const std::string& name) {
  if (fit.flags & kNodeUnrejectable) return;  // always accepts
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int with = 0, bad = 0;
  for (int i = 0; i < 20000; ++i) {
    Vec3 p = center + 3 * size * Vec3(u(rng), u(rng), u(rng));
    if (i % 2) {  // project onto one of the planes (exactly-on-plane points up to rounding)
      const Wedge& w = wedges[size_t(i / 2) % wedges.size()];
      const Vec4 q = (i / 2) % 2 ? w.q0 : w.q1;
      p -= (q.head<3>().dot(p) + q[3]) * q.head<3>();
    }
    bool sil = false;
    for (const Wedge& w : wedges) {
      const double g0 = w.q0.head<3>().dot(p) + w.q0[3], g1 = w.q1.head<3>().dot(p) + w.q1[3];
      sil = sil || g0 * g1 <= 0.0;
    }
    if (!sil) continue;
    ++with;
    if (!bound_may_have_silhouette(fit.bound, fit.flags & kNodeBoxOnly, p)) ++bad;
    if (!bound_may_have_silhouette(fit.bound, true, p)) ++bad;
  }
  EXPECT_GT(with, 0) << name;
  EXPECT_EQ(bad, 0) << name;
}

std::vector<Vec4> planes_of(const std::vector<Wedge>& w) {
  std::vector<Vec4> p;
  for (const auto& x : w) {
    p.push_back(x.q0);
    p.push_back(x.q1);
  }
  return p;
}

Box3 box_of(const Vec3& c, double s) {
  Box3 b;
  b.expand(c - Vec3::Constant(s));
  b.expand(c + Vec3::Constant(s));
  return b;
}

// A parent with a real quadric (planes tangent to a sphere) so that small children inherit it.
NodeFit sphere_parent(const Vec3& c, double r) {
  std::vector<Wedge> w;
  std::mt19937_64 rng(99);
  std::normal_distribution<double> g;
  for (int i = 0; i < 40; ++i) {
    Vec3 n0(g(rng), g(rng), std::abs(g(rng)) + 2), n1 = n0 + 0.2 * Vec3(g(rng), g(rng), g(rng));
    w.push_back({plane_of(n0, c + r * n0.normalized()), plane_of(n1, c + r * n1.normalized())});
  }
  return fit_node(planes_of(w), w, box_of(c, r), nullptr);
}

TEST(ForestDegeneratePatch, SingleWedgeBoxAndInherited) {
  for (double scale : {1.0, 1e-4, 1e4}) {
    for (const Vec3& off : {Vec3(0, 0, 0), Vec3(1e4, 2e4, -1e4)}) {
      const Vec3 c = off + Vec3(0.1, 0.2, 0.3) * scale;
      const std::vector<Wedge> w = {{plane_of(Vec3(0, 0.3, 1), c), plane_of(Vec3(0, -0.3, 1), c)}};
      const NodeFit alone = fit_node(planes_of(w), w, box_of(c, 0.01 * scale), nullptr);
      EXPECT_TRUE(alone.flags & kNodeBoxOnly);
      expect_bound_sound(alone, w, 0.01 * scale, c, 1, "single wedge");
      const NodeFit parent = sphere_parent(c - Vec3(0, 0, scale), scale);
      const NodeFit child = fit_node(planes_of(w), w, box_of(c, 0.01 * scale), &parent);
      EXPECT_TRUE(child.flags & kNodeInherited);
      EXPECT_FALSE(child.flags & kNodeBoxOnly);
      expect_bound_sound(child, w, 0.01 * scale, c, 2, "single wedge inherited");
    }
  }
}

TEST(ForestDegeneratePatch, PlanarAndNearlyParallel) {
  const Vec3 c(0.5, -0.2, 0.1);
  const NodeFit parent = sphere_parent(c - Vec3(0, 0, 1), 1.0);
  for (double angle : {0.0, 1e-12, 1e-7, 1e-3}) {
    std::vector<Wedge> w;
    for (int i = 0; i < 20; ++i) {
      const Vec3 x = c + 0.05 * Vec3(i % 5, i / 5, 0);
      w.push_back({plane_of(Vec3(0, std::sin(angle), std::cos(angle)), x),
                   plane_of(Vec3(0, -std::sin(angle), std::cos(angle)), x)});
    }
    for (const NodeFit* par : {static_cast<const NodeFit*>(nullptr), &parent}) {
      const NodeFit fit = fit_node(planes_of(w), w, box_of(c, 0.2), par);
      expect_bound_sound(fit, w, 0.2, c, 3, "planar angle " + std::to_string(angle));
    }
  }
}

}  // namespace
}  // namespace qsil::edgetree
