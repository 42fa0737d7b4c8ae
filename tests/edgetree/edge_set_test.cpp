/// @file edge_set_test.cpp
/// The edge set's hierarchy (edge_set.h, docs/architecture.md §5 "Tree"): its shape does not depend
/// on the thread count (a level's splits run in parallel), its leaves hold edges that lie together
/// (the splits order EdgeBoxRef records and the edges follow them once: edges in an order other
/// than the records' would scatter every leaf over the mesh), every node's range is its children's
/// and belongs to its shape, in a scene of several shapes of very different sizes.

#include "qsil/edgetree/edge_set.h"
#include "edgetree/sah_split.h"
#include "qsil/scene.h"

#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include "soundness_set.h"
#include "test_data.h"

namespace qsil::edgetree {
namespace {

EdgeSet build_with_threads(std::span<const ForestShapeInput> in, int threads) {
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, size_t(threads));
  return EdgeSet::build(in);
}

/// `m` with its vertices renumbered by a random permutation (seed `seed`); the same surface.
TriangleMesh shuffled_vertices(const TriangleMesh& m, unsigned seed) {
  std::vector<int> to(size_t(m.num_vertices()));
  std::iota(to.begin(), to.end(), 0);
  std::mt19937 rng(seed);
  std::shuffle(to.begin(), to.end(), rng);
  TriangleMesh r = m;
  for (size_t v = 0; v < to.size(); ++v) {
    r.positions[size_t(to[v])] = m.positions[v];
    if (!m.normals.empty()) r.normals[size_t(to[v])] = m.normals[v];
  }
  for (auto& t : r.triangles)
    for (int k = 0; k < 3; ++k) t[k] = to[size_t(t[k])];
  return r;
}

TEST(EdgeSetHierarchy, DoesNotDependOnTheThreadCount) {
  // Spot, and two spheres that cross (its intersection curves are found beside the trees).
  const TriangleMesh spot = load_obj(test::mesh_file("spot.obj"));
  const TriangleMesh spheres = load_obj(test::data_file("tests/data/meshes/two-spheres.obj"));
  for (const TriangleMesh* mesh : {&spot, &spheres}) {
    ForestShapeInput in{mesh, 0};
    in.creases = CreaseSet::Concave;
    const EdgeSet one = build_with_threads(std::span(&in, 1), 1);
    const EdgeSet two = build_with_threads(std::span(&in, 1), 2);
    EXPECT_EQ(one.crossings().size(), two.crossings().size());
    if (mesh == &spheres) {
      EXPECT_GT(one.crossings().size(), 10u);
    }
    ASSERT_EQ(one.nodes().size(), two.nodes().size());
    for (size_t i = 0; i < one.nodes().size(); ++i) {
      const ForestNode &a = one.nodes()[i], &b = two.nodes()[i];
      EXPECT_EQ(std::tie(a.first, a.count, a.edge_begin, a.edge_end, a.parent, a.flags, a.lw),
                std::tie(b.first, b.count, b.edge_begin, b.edge_end, b.parent, b.flags, b.lw))
          << "node " << i;
      EXPECT_TRUE(a.bp.lo == b.bp.lo && a.bp.hi == b.bp.hi) << "node " << i;
    }
    ASSERT_EQ(one.edges().size(), two.edges().size());
    for (size_t k = 0; k < one.edges().size(); ++k)
      EXPECT_EQ(std::tie(one.edges()[k].v0, one.edges()[k].v1), std::tie(two.edges()[k].v0, two.edges()[k].v1));
    ASSERT_EQ(one.always_edges().size(), two.always_edges().size());
    for (size_t k = 0; k < one.always_edges().size(); ++k) {
      EXPECT_EQ(one.always_edges()[k].v0, two.always_edges()[k].v0);
      EXPECT_EQ(one.always_edges()[k].p0, two.always_edges()[k].p0);
      EXPECT_EQ(one.always_edges()[k].p1, two.always_edges()[k].p1);
    }
  }
}

TEST(SahSplit, ParallelScanSplitsAsTheSerialOne) {
  // 100 000 edges (above kParallelSplitEdges) whose density grows along x, in x order (so that a
  // scan's chunks are slabs: a chunk counted wrongly moves the best split), split by the serial
  // and by the parallel scan (2 threads): the same first part, and the same order of records.
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, 2);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> xs(100000);
  for (double& x : xs) x = std::sqrt(0.5 * (u(rng) + 1.0));
  std::sort(xs.begin(), xs.end());
  std::vector<EdgeBoxRef> refs;
  for (size_t k = 0; k < xs.size(); ++k) {
    const Vec3 c(xs[k], 0.3 * u(rng), 0.3 * u(rng));
    const Vec3 d = 0.01 * Vec3(u(rng), u(rng), u(rng));
    refs.push_back(edge_box_ref(Vec3(c - d), Vec3(c + d), int(k)));
  }
  ASSERT_GE(int(refs.size()), kParallelSplitEdges);
  for (int buckets : {2, 10, 32}) {
    std::vector<EdgeBoxRef> serial = refs, parallel = refs;
    const int m_serial = sah_split(serial, buckets, INT_MAX);
    const int m_parallel = sah_split(parallel, buckets, 1);
    EXPECT_EQ(m_serial, m_parallel) << buckets << " buckets";
    EXPECT_GT(m_serial, 0);
    EXPECT_LT(m_serial, int(refs.size()));
    bool same = true;
    for (size_t k = 0; k < refs.size(); ++k) same = same && serial[k].index == parallel[k].index;
    EXPECT_TRUE(same) << buckets << " buckets";
  }
}

TEST(EdgeSetHierarchy, LeavesHoldEdgesThatLieTogether) {
  // Spot (smooth: a silhouette tree and a crease tree) and the torus (flat: creases only), their
  // vertices renumbered at random: the edges then reach the build in no spatial order (a mesh's
  // own numbering is coherent enough to hide a build that ignores the splits' order).
  const TriangleMesh spot = shuffled_vertices(load_obj(test::mesh_file("spot.obj")), 1);
  const TriangleMesh torus = shuffled_vertices(load_obj(test::mesh_file("torus.obj")), 2);
  for (const bool flat : {false, true}) {
    ForestShapeInput in{flat ? &torus : &spot, 0};
    in.face_normals = flat;
    in.creases = CreaseSet::Concave;
    const EdgeSet set = EdgeSet::build(std::span(&in, 1));
    // For each leaf: its box's diagonal over its longest edge. Four edges that share a
    // neighbourhood give a few; four edges of a mesh scattered at random give about the mesh's
    // size over an edge's.
    std::vector<double> ratio;
    for (size_t i = 0; i < set.nodes().size(); ++i) {
      const ForestNode& n = set.nodes()[i];
      if (!n.is_leaf()) continue;
      double longest = 0;
      for (const Edge& e : set.node_edges(int(i))) longest = std::max(longest, e.length);
      ASSERT_GT(longest, 0);
      ratio.push_back(n.bp.diagonal() / longest);
    }
    ASSERT_GT(ratio.size(), 100u);
    std::sort(ratio.begin(), ratio.end());
    EXPECT_LT(ratio[ratio.size() / 2], 2.5) << (flat ? "torus" : "spot") << ": median leaf box over its longest edge";
    EXPECT_LT(ratio[ratio.size() * 9 / 10], 4.0) << (flat ? "torus" : "spot") << ": 90th percentile";
  }
}

TEST(EdgeSetHierarchy, RangesNestAndBelongToTheirShape) {
  // A large shape, then a small one, then a large one again: the arrays the shapes share are
  // appended to shape after shape.
  const TriangleMesh spot = load_obj(test::mesh_file("spot.obj"));
  const TriangleMesh cube = test::make_cube(2);
  const TriangleMesh bunny = load_obj(test::mesh_file("bunny.obj"));
  std::vector<ForestShapeInput> in{{&spot, 0}, {&cube, 1}, {&bunny, 2}};
  in[1].face_normals = true;
  for (ForestShapeInput& s : in) s.creases = CreaseSet::Concave;
  EdgeSetOptions opt;
  opt.intersection_curves = false;
  const EdgeSet set = EdgeSet::build(in, opt);
  std::vector<int> tree_edges(3, 0), always_edges(3, 0);
  for (size_t i = 0; i < set.nodes().size(); ++i) {
    const ForestNode& n = set.nodes()[i];
    const std::vector<Edge>& arr = n.always() ? set.always_edges() : set.edges();
    ASSERT_LT(n.edge_begin, n.edge_end);
    ASSERT_LE(n.edge_end, int(arr.size()));
    for (int k = n.edge_begin; k < n.edge_end; ++k) {
      const Edge& e = arr[size_t(k)];
      ASSERT_EQ(e.shape, n.shape) << "node " << i;
      EXPECT_TRUE((n.bp.lo.array() <= e.p0.cwiseMin(e.p1).array()).all() &&
                  (e.p0.cwiseMax(e.p1).array() <= n.bp.hi.array()).all())
          << "node " << i << " edge " << k;
    }
    if (n.is_leaf()) {
      EXPECT_EQ(n.first, n.edge_begin);
      EXPECT_EQ(n.first + n.count, n.edge_end);
      (n.always() ? always_edges : tree_edges)[size_t(n.shape)] += n.count;
      continue;
    }
    int at = n.edge_begin;
    for (int c = n.first; c < n.first + n.count; ++c) {
      EXPECT_EQ(set.nodes()[size_t(c)].edge_begin, at) << "child " << c << " of node " << i;
      EXPECT_EQ(set.nodes()[size_t(c)].parent, int(i));
      at = set.nodes()[size_t(c)].edge_end;
    }
    EXPECT_EQ(at, n.edge_end) << "node " << i;
  }
  // Every edge of every tree sits in exactly one leaf.
  for (int s = 0; s < 3; ++s) {
    EXPECT_EQ(tree_edges[size_t(s)], set.stats()[size_t(s)].edges_kept) << "shape " << s;
    EXPECT_EQ(always_edges[size_t(s)],
              set.stats()[size_t(s)].always_nodes > 0 ? set.stats()[size_t(s)].edges_always : 0)
        << "shape " << s;
  }
  EXPECT_EQ(tree_edges[1], 0);  // flat-shaded: no silhouette tree
  EXPECT_GT(always_edges[1], 0);
}

}  // namespace
}  // namespace qsil::edgetree
