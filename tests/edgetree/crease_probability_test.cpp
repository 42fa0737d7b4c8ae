/// @file crease_probability_test.cpp
/// Soundness of the traversal over a smooth-shaded shape's creases: Spot built as the renderer
/// builds a one-sided smooth shape (CreaseSet::Concave: its 2602 concave edges are creases, in an
/// always-candidate tree of box-only nodes that competes with the silhouette forest's roots), for
/// shading points around it with diffuse or GGX LTCs. Every discontinuity edge, each crease
/// included, must keep a probability > 0 in the traversal (silhouette_edge_probability, which walks
/// the same choices, the flat choices included; a zero would be bias: that edge's boundary
/// integral is never estimated), and the probabilities sum to at most 1. The forest soundness and
/// split-sampling tests build their forests without creases, so the always-candidate trees of
/// smooth shapes are checked here. Fixed seeds; deterministic.

#include "baselines/baseline_test_util.h"
#include "qsil/edgetree/edge_forest.h"
#include "qsil/edgetree/ltc.h"
#include "qsil/edgetree/silhouette_sampler.h"
#include "qsil/method.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace qsil::edgetree {
namespace {

using namespace qsil::baselines_test;

TEST(SmoothCreases, EveryCreaseOfASmoothShapeKeepsProbabilityAndTheySumToAtMostOne) {
  std::vector<TriangleMesh> meshes{test_mesh("spot.obj")};
  const std::vector<ForestShapeInput> in{{&meshes[0], 0, /*face_normals=*/false, CreaseSet::Concave}};
  const EdgeForest forest = EdgeForest::build(in);
  int creases = 0;
  for (const ForestEdge& e : forest.always_edges()) creases += e.crease;
  ASSERT_GT(creases, 2000) << "Spot's concave edges must be creases";
  ASSERT_FALSE(forest.always_roots().empty()) << "the creases must be in an always-candidate tree";

  const std::vector<bool> eligible{true};
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(0, 1);
  const std::vector<Vec3> pts = shading_points(meshes[0], 16, 5);
  for (Method m : {Method::Quadric, Method::QuadricBox}) {
    int missing = 0, over = 0, edges = 0, crease_edges = 0;
    for (size_t i = 0; i < pts.size(); ++i) {
      SilhouetteQuery q;
      q.p = pts[i];
      q.frame = Frame(Vec3(g(rng), g(rng), g(rng)).normalized());
      if (i % 2) {
        q.ltc = ltc_diffuse();
        q.ltc.norm = 0.7;
      } else {
        q.ltc = ltc_ggx(std::pow(10.0, -1.5 + 1.5 * u(rng)), Vec3(g(rng), g(rng), std::abs(g(rng)) + 0.1).normalized());
      }
      q.eligible = &eligible;
      double sum = 0;
      auto check = [&](const ForestEdge& e) {
        const double pr = silhouette_edge_probability(forest, q, &e, m);
        sum += pr;
        if (!is_discontinuity(e, q.p)) return;
        ++edges;
        crease_edges += e.crease;
        missing += !(pr > 0);
      };
      for (const ForestEdge& e : forest.edges()) check(e);
      for (const ForestEdge& e : forest.always_edges()) check(e);
      over += sum > 1 + 1e-9;
    }
    EXPECT_GT(crease_edges, 16 * 2000) << method_name(m) << ": too few creases for power";
    EXPECT_EQ(missing, 0) << method_name(m) << ": of " << edges << " discontinuity edges";
    EXPECT_EQ(over, 0) << method_name(m) << ": probabilities summing to more than 1";
  }
}

}  // namespace
}  // namespace qsil::edgetree
