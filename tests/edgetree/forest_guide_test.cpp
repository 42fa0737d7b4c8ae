/// @file forest_guide_test.cpp
/// The forest guide (forest_guide.h) and the guided traversal (silhouette_sampler.h) on a forest
/// of spot (its concave edges creases in an always-candidate tree) and an emitting open square
/// sheet (its outline loose always-candidate edges):
/// - the slots are exactly the roots, the always-candidate roots, the loose edges and the nodes to
///   the guide's depth below the roots, each with a slot of its own in [0, slots);
/// - training adds each record's value to its slot in its point's cell, skips invalid records,
///   and bins a point outside the box in the nearest cell;
/// - with a guide trained on random records, the traversal's edge choices match the probabilities
///   of the path mixture (traversal_edge_probability, which walks the same choices): chi-square,
///   1 % family significance (Šidák), 40000 traversals per query, pdf = probability × density of
///   t (relative 1e-9); every silhouette edge keeps a probability >= s × its unguided one, and
///   they sum to at most 1. Power: the guide must move some edge's probability by 2× or more.
/// Fixed seeds.

#include "qsil/edgetree/forest_guide.h"
#include "baselines/baseline_test_util.h"
#include "chi2.h"
#include "edgetree/edge_mixture.h"
#include "qsil/edgetree/edge_forest.h"
#include "qsil/edgetree/ltc.h"
#include "qsil/edgetree/quadric_sampler.h"
#include "qsil/edgetree/silhouette_sampler.h"
#include "qsil/error.h"
#include "qsil/rng.h"
#include "spot_sheet_world.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <random>

namespace qsil::edgetree {
namespace {

using namespace qsil::baselines_test;
using namespace qsil::test;

/// Spot with its concave edges creases and the sheet beside it (spot_sheet_world.h).
std::unique_ptr<test::SpotSheetWorld> make_world() { return test::make_spot_sheet_world(CreaseSet::Concave, 0.6, 1.1); }

/// The depth of every node below the roots and always-candidate roots (-1: none reached).
std::vector<int> node_depths(const EdgeForest& f) {
  std::vector<int> depth(f.nodes().size(), -1);
  std::vector<int> stack;
  for (int r : f.roots()) depth[size_t(r)] = 0, stack.push_back(r);
  for (int r : f.always_roots()) depth[size_t(r)] = 0, stack.push_back(r);
  while (!stack.empty()) {
    const int n = stack.back();
    stack.pop_back();
    const ForestNode& node = f.node(n);
    if (node.is_leaf()) continue;
    for (int c = node.first; c < node.first + node.count; ++c) {
      depth[size_t(c)] = depth[size_t(n)] + 1;
      stack.push_back(c);
    }
  }
  return depth;
}

TEST(ForestGuide, SlotsAreTheUpperLevels) {
  const auto w = make_world();
  const EdgeForest& f = w->forest;
  ASSERT_FALSE(f.always_roots().empty());
  ASSERT_FALSE(f.loose_always_edges().empty());
  const std::vector<int> depth = node_depths(f);
  for (int D : {0, 2, 3}) {
    const ForestGuide g(f, {8, D, 0.5});
    int expected = int(f.loose_always_edges().size());
    std::vector<int> seen;  // every slot handed out, once each
    for (int n = 0; n < int(f.nodes().size()); ++n) {
      const bool guided = depth[size_t(n)] >= 0 && depth[size_t(n)] <= D;
      expected += guided;
      ASSERT_EQ(g.node_slot(n) >= 0, guided) << "node " << n << " at depth " << depth[size_t(n)] << ", D " << D;
      if (guided) seen.push_back(g.node_slot(n));
    }
    for (int i : f.loose_always_edges()) {
      ASSERT_GE(g.loose_edge_slot(i), 0);
      seen.push_back(g.loose_edge_slot(i));
    }
    EXPECT_EQ(g.slots(), expected) << "D " << D;
    std::sort(seen.begin(), seen.end());
    ASSERT_EQ(int(seen.size()), g.slots());
    for (int s = 0; s < g.slots(); ++s) EXPECT_EQ(seen[size_t(s)], s) << "slots not distinct in [0, slots), D " << D;
  }
  EXPECT_THROW(ForestGuide(f, {0, 3, 0.5}), Error);
  EXPECT_THROW(ForestGuide(f, {8, 9, 0.5}), Error);
  EXPECT_THROW(ForestGuide(f, {8, 3, 0.0}), Error);
}

TEST(ForestGuide, TrainingAddsToTheSlotInItsCell) {
  const auto w = make_world();
  ForestGuide g(w->forest, {4, 3, 0.5});
  EXPECT_EQ(g.cell_values(Vec3::Zero()), nullptr) << "an untrained guide guides nothing";
  // The slot of a node at depth 2.
  const std::vector<int> depth = node_depths(w->forest);
  int slot = -1;
  for (int n = 0; n < int(depth.size()) && slot < 0; ++n)
    if (depth[size_t(n)] == 2) slot = g.node_slot(n);
  ASSERT_GE(slot, 0);
  const Vec3 a(0, 0, 0), b(1, 1, 1);
  const double nan = std::nan("");
  g.train({{a, slot, 2.0},
           {b, slot, 1.0},
           {a, slot, 0.5},
           {a, -1, 7.0},
           {a, slot, nan},
           {a, slot, -3.0},
           {Vec3(nan, 0, 0), slot, 9.0}});
  const double* va = g.cell_values(a);
  ASSERT_NE(va, nullptr);
  EXPECT_EQ(g.occupied_cells(), 2);
  for (int s = 0; s < g.slots(); ++s) {
    EXPECT_EQ(va[s], s == slot ? 2.5 : 0.0) << "slot " << s;
    EXPECT_EQ(va[g.slots() + s], s == slot ? 2.0 : 0.0) << "records of slot " << s;
  }
  // Outside the box: the nearest cell.
  EXPECT_EQ(g.cell_values(Vec3(-5, -5, -5)), va);
  EXPECT_EQ(g.cell_values(Vec3(5, 5, 5)), g.cell_values(b));
  EXPECT_EQ(g.cell_values(b)[slot], 1.0);
  EXPECT_EQ(g.cell_values(Vec3(1, 0, 0)), nullptr) << "a cell without records guides nothing";
  // Records on a plane one ulp thick: a point far off it lands in the nearest cell (no overflow).
  const double y0 = 0.1, y1 = std::nextafter(0.1, 1.0);
  g.train({{Vec3(0, y0, 0), slot, 1.0}, {Vec3(1, y1, 1), slot, 3.0}});
  ASSERT_NE(g.cell_values(Vec3(1, y1, 1)), nullptr);
  EXPECT_EQ(g.cell_values(Vec3(1, 1e6, 1)), g.cell_values(Vec3(1, y1, 1)));
  EXPECT_EQ(g.cell_values(Vec3(0, -1e300, 0)), g.cell_values(Vec3(0, y0, 0)));
  EXPECT_EQ(g.cell_values(Vec3(1, std::numeric_limits<double>::infinity(), 1)), g.cell_values(Vec3(1, y1, 1)));
}

TEST(ForestGuide, GuidedChoicesMatchThePathMixture) {
  const auto w = make_world();
  const EdgeForest& f = w->forest;
  ForestGuide guide(f, {2, 3, 0.3});
  // Random records over spot's box: random slots, values spread over six decades, some slots none.
  std::mt19937_64 rng(57);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<GuideRecord> records;
  for (int i = 0; i < 4000; ++i) {
    const int slot = int(u(rng) * guide.slots());
    if (slot % 5 == 0) continue;
    records.push_back({Vec3(u(rng) - 0.5, u(rng) + 0.2, u(rng) - 0.5), slot, std::pow(10.0, 6 * u(rng) - 3)});
  }
  guide.train(records);
  const std::vector<Vec3> pts = shading_points(w->meshes[0], 24, 58);
  const QuadricEdgeSampler sampler(f, NodeTest::DualBoxAndQuadrics);
  std::normal_distribution<double> gauss;
  const int n = 40000;
  const int tested = 6;
  const double alpha = sidak(0.01, tested);
  double largest_ratio = 1;
  for (int qi = 0; qi < tested; ++qi) {
    SilhouetteQuery q;
    q.p = pts[size_t(qi)];
    q.frame = Frame(Vec3(gauss(rng), gauss(rng) + 1.5, gauss(rng)).normalized());
    q.ltc = ltc_diffuse();
    q.ltc.norm = 0.7;
    q.eligible = &w->eligible;
    q.emission = &w->emission;
    q.env_weight = 0.05;
    SilhouetteQuery unguided = q;
    q.guide = &guide;
    ASSERT_NE(guide.cell_values(q.p), nullptr);
    const auto split = split_edges(f, q, NodeTest::DualBoxAndQuadrics);
    auto is_split = [&](const Edge* e) { return std::find(split.begin(), split.end(), e) != split.end(); };
    std::map<const Edge*, int> bin;
    std::vector<double> expected(1, 0.0);  // bin 0: no traversal sample
    double mass = 0;
    auto add = [&](const Edge& e) {
      if (is_split(&e) || !is_discontinuity(e, q.p)) return;
      const double pr = traversal_edge_probability(f, q, &e, NodeTest::DualBoxAndQuadrics);
      const double pu = traversal_edge_probability(f, unguided, &e, NodeTest::DualBoxAndQuadrics);
      EXPECT_GE(pr, (1 - 1e-12) * guide.share() * pu) << "query " << qi << ": below the defensive share";
      if (pu > 0) largest_ratio = std::max({largest_ratio, pr / pu, pu / pr});
      if (!(pr > 0)) return;
      bin[&e] = int(expected.size());
      expected.push_back(n * pr);
      mass += pr;
    };
    for (const Edge& e : f.edges()) add(e);
    for (const Edge& e : f.always_edges()) add(e);
    ASSERT_LE(mass, 1 + 1e-9) << "query " << qi;
    expected[0] = n * std::max(0.0, 1.0 - mass);
    std::vector<double> observed(expected.size(), 0.0);
    Sampler s_rng(92, uint64_t(qi), 0);
    int bad_pdf = 0, unknown = 0;
    SilhouetteSampleSet set;
    for (int i = 0; i < n; ++i) {
      sampler.sample_set(
          q, [&] { return s_rng.next(); }, set);
      bool traversal = false;
      for (int k = 0; k < set.count; ++k) {
        const SilhouetteSample& s = set.samples[size_t(k)];
        if (is_split(s.edge)) continue;
        traversal = true;
        auto it = bin.find(s.edge);
        if (it == bin.end()) {
          ++unknown;
          continue;
        }
        observed[size_t(it->second)] += 1;
        const double want = expected[size_t(it->second)] / n * EdgeMixture(*s.edge, q).pdf(s.t);
        bad_pdf += !(std::abs(s.pdf - want) <= 1e-9 * want);
      }
      if (!traversal) observed[0] += 1;
    }
    EXPECT_EQ(unknown, 0) << "query " << qi << ": an edge of probability 0";
    EXPECT_EQ(bad_pdf, 0) << "query " << qi << ": pdf != probability x density of t";
    const Chi2Result r = chi2_test(observed, expected, alpha);
    EXPECT_TRUE(r.passed) << "query " << qi << ": " << r.message;
  }
  EXPECT_GE(largest_ratio, 2.0) << "the guide changed no probability much: the test has no power";
}

}  // namespace
}  // namespace qsil::edgetree
