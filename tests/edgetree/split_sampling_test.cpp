/// @file split_sampling_test.cpp
/// Splitting in the edge forest's traversal (sample_silhouette_set, silhouette_sampler.h) on a
/// forest of spot and an emitting open square sheet (radiance 40: its outline is loose
/// always-candidate and bright), for shading points around spot with diffuse or GGX LTCs:
/// - the split set is exactly the loose edges whose top-level probability (sample_silhouette's,
///   silhouette_edge_probability) is >= kSplitShare, at most kMaxSplitEdges of them;
/// - every set holds one point of each split edge (pdf = the split edge's density of t alone)
///   and at most one traversal sample, of a non-split edge;
/// - the traversal's choices: chi-square against traversal_edge_probability for every non-split
///   silhouette edge plus a "no edge" bin, 1 % family significance (Šidák), 40000 traversals per
///   query; its pdf = that probability × the edge's density of t (relative 1e-9);
/// - the choice among the rest is made afresh: where every loose edge is split, the traversal's
///   probabilities are sample_silhouette's in the same world without the sheet (an oracle that
///   walks a different top level), not sample_silhouette's divided by 1 - the split sum;
/// - every discontinuity edge has a traversal probability > 0, and they sum to at most 1, with
///   Spot's concave edges left out of the forest and with them as creases (always-candidate tree).
/// The split tests have power only if some queries split: they require at least 3 of the queries to.
/// Fixed seeds.

#include "baselines/baseline_test_util.h"
#include "chi2.h"
#include "edgetree/edge_mixture.h"
#include "qsil/edgetree/edge_forest.h"
#include "qsil/edgetree/ltc.h"
#include "qsil/edgetree/quadric_sampler.h"
#include "qsil/edgetree/silhouette_sampler.h"
#include "qsil/rng.h"
#include "spot_sheet_world.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <memory>
#include <random>
#include <string>

namespace qsil::edgetree {
namespace {

using namespace qsil::baselines_test;
using namespace qsil::test;

using World = test::SpotSheetWorld;

/// Spot with its creases as `spot_creases` says and the sheet above it (spot_sheet_world.h).
std::unique_ptr<World> make_world(CreaseSet spot_creases = CreaseSet::None) {
  return test::make_spot_sheet_world(spot_creases, 0.4, 1.2);
}

std::vector<SilhouetteQuery> queries(const World& w, int n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(0, 1);
  const std::vector<Vec3> pts = shading_points(w.meshes[0], n, seed);
  std::vector<SilhouetteQuery> out(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    SilhouetteQuery& q = out[i];
    q.p = pts[i];
    q.frame = Frame(Vec3(g(rng), g(rng) + 1.5, g(rng)).normalized());  // mostly facing the sheet
    if (i % 2) {
      q.ltc = ltc_diffuse();
      q.ltc.norm = 0.7;
    } else {
      q.ltc = ltc_ggx(std::pow(10.0, -1.5 + 1.5 * u(rng)), Vec3(g(rng), g(rng), std::abs(g(rng)) + 0.1).normalized());
    }
    q.eligible = &w.eligible;
    q.emission = &w.emission;
    q.env_weight = 0.05;
  }
  return out;
}

TEST(SplitSampling, SplitSetIsTheBrightLooseEdges) {
  const auto w = make_world();
  const auto qs = queries(*w, 60, 41);
  int splitting = 0;
  for (size_t qi = 0; qi < qs.size(); ++qi) {
    const SilhouetteQuery& q = qs[qi];
    double sum = 0;
    const auto split = split_edges(w->forest, q, NodeTest::DualBoxAndQuadrics, &sum);
    std::vector<std::pair<double, const Edge*>> want;
    for (const Edge& e : w->forest.always_edges()) {
      const double pr = silhouette_edge_probability(w->forest, q, &e, NodeTest::DualBoxAndQuadrics);
      if (pr >= kSplitShare) want.push_back({pr, &e});
    }
    std::sort(want.rbegin(), want.rend());
    if (want.size() > size_t(kMaxSplitEdges)) want.resize(size_t(kMaxSplitEdges));
    double want_sum = 0;
    for (const auto& x : want) want_sum += x.first;
    ASSERT_EQ(split.size(), want.size()) << "query " << qi;
    for (const auto& x : want)
      EXPECT_NE(std::find(split.begin(), split.end(), x.second), split.end()) << "query " << qi;
    EXPECT_NEAR(sum, want_sum, 1e-12) << "query " << qi;
    splitting += !split.empty();
  }
  EXPECT_GE(splitting, 3) << "too few queries split: the test has no power";
}

TEST(SplitSampling, TraversalHistogramMatchesRenormalisedProbabilities) {
  const auto w = make_world();
  const auto qs = queries(*w, 24, 42);
  const QuadricEdgeSampler sampler(w->forest, NodeTest::DualBoxAndQuadrics);
  const int n = 40000;
  std::vector<size_t> tested;
  for (size_t qi = 0; qi < qs.size(); ++qi)
    if (!split_edges(w->forest, qs[qi], NodeTest::DualBoxAndQuadrics).empty()) tested.push_back(qi);
  ASSERT_GE(tested.size(), 3u) << "too few queries split: the test has no power";
  if (tested.size() > 6) tested.resize(6);
  const double alpha = sidak(0.01, int(tested.size()));
  for (size_t qi : tested) {
    const SilhouetteQuery& q = qs[qi];
    double split_sum = 0;
    const auto split = split_edges(w->forest, q, NodeTest::DualBoxAndQuadrics, &split_sum);
    auto is_split = [&](const Edge* e) { return std::find(split.begin(), split.end(), e) != split.end(); };
    std::map<const Edge*, int> bin;
    std::vector<double> expected(1, 0.0);  // bin 0: no traversal sample
    double mass = 0;
    auto add = [&](const Edge& e) {
      if (is_split(&e) || !edge_is_silhouette(e, q.p)) return;
      const double pr = traversal_edge_probability(w->forest, q, &e, NodeTest::DualBoxAndQuadrics);
      if (!(pr > 0)) return;
      bin[&e] = int(expected.size());
      expected.push_back(n * pr);
      mass += pr;
    };
    for (const Edge& e : w->forest.edges()) add(e);
    for (const Edge& e : w->forest.always_edges()) add(e);
    expected[0] = n * std::max(0.0, 1.0 - mass);
    std::vector<double> observed(expected.size(), 0.0);
    Sampler rng(91, qi, 0);
    int bad_split = 0, bad_pdf = 0, unknown = 0, extra = 0;
    SilhouetteSampleSet set;
    for (int i = 0; i < n; ++i) {
      sampler.sample_set(q, [&] { return rng.next(); }, set);
      int seen_split = 0, traversal = 0;
      for (int k = 0; k < set.count; ++k) {
        const SilhouetteSample& s = set.samples[size_t(k)];
        const double pdf_t = EdgeMixture(*s.edge, q).pdf(s.t);
        if (is_split(s.edge)) {
          ++seen_split;
          bad_pdf += !(std::abs(s.pdf - pdf_t) <= 1e-9 * pdf_t);
          continue;
        }
        ++traversal;
        auto it = bin.find(s.edge);
        if (it == bin.end()) {
          ++unknown;
          continue;
        }
        observed[size_t(it->second)] += 1;
        const double want = expected[size_t(it->second)] / n * pdf_t;
        bad_pdf += !(std::abs(s.pdf - want) <= 1e-9 * want);
      }
      bad_split += seen_split != int(split.size());
      extra += traversal > 1;
      if (traversal == 0) observed[0] += 1;
    }
    EXPECT_EQ(bad_split, 0) << "query " << qi << ": a set without every split edge";
    EXPECT_EQ(extra, 0) << "query " << qi << ": more than one traversal sample";
    EXPECT_EQ(unknown, 0) << "query " << qi << ": the traversal sampled a split edge or one of probability 0";
    EXPECT_EQ(bad_pdf, 0) << "query " << qi << ": pdf != probability x density of t";
    const Chi2Result r = chi2_test(observed, expected, alpha);
    EXPECT_TRUE(r.passed) << "query " << qi << ": " << r.message;
  }
}

// Where the split set is all of the sheet's outline (its only candidates), the traversal chooses
// among spot's candidates alone as if the sheet were not there: traversal_edge_probability equals
// silhouette_edge_probability with the sheet ineligible, for every silhouette edge of spot
// (relative 1e-9). Dividing the probabilities with the sheet by 1 - the split sum instead (what the
// traversal did before) keeps the defensive part at its size beside the sheet's importance and
// differs by up to ~10x for some edges of these queries (the test's message says by how much).
TEST(SplitSampling, ChoiceAmongTheRestIsMadeAfresh) {
  const auto w = make_world();
  const auto qs = queries(*w, 60, 43);
  const std::vector<bool> spot_only{true, false};
  int tested = 0, bad = 0, edges = 0;
  double largest_old_ratio = 1.0;
  for (const SilhouetteQuery& q : qs) {
    double split_sum = 0;
    if (split_edges(w->forest, q, NodeTest::DualBoxAndQuadrics, &split_sum).size() != w->forest.always_edges().size()) continue;
    ++tested;
    SilhouetteQuery without = q;
    without.eligible = &spot_only;
    for (const Edge& e : w->forest.edges()) {
      if (!edge_is_silhouette(e, q.p)) continue;
      const double want = silhouette_edge_probability(w->forest, without, &e, NodeTest::DualBoxAndQuadrics);
      const double got = traversal_edge_probability(w->forest, q, &e, NodeTest::DualBoxAndQuadrics);
      ++edges;
      bad += !(std::abs(got - want) <= 1e-9 * want);
      const double old = silhouette_edge_probability(w->forest, q, &e, NodeTest::DualBoxAndQuadrics) / (1.0 - split_sum);
      if (old > 0 && want > 0) largest_old_ratio = std::max({largest_old_ratio, want / old, old / want});
    }
  }
  ASSERT_GE(tested, 3) << "too few queries split the whole outline: the test has no power";
  EXPECT_GT(edges, 100);
  EXPECT_EQ(bad, 0) << "of " << edges << " silhouette edges over " << tested
                    << " queries (the old renormalisation would be off by up to " << largest_old_ratio << "x)";
  EXPECT_GT(largest_old_ratio, 1.1) << "the queries cannot tell the two renormalisations apart";
}

// The traversal's edge probabilities (silhouette_edge_probability, which walks the same choices,
// the flat choice of small subtrees included) are a sub-probability over the discontinuity edges
// that misses none: for the queries of the world above, every discontinuity edge of an eligible
// shape has probability > 0 (a zero would be bias: that edge's boundary integral is never
// estimated), and they sum to at most 1 (the rest: traversals that find no edge). Both methods;
// the histogram test above checks that the sampler draws with these probabilities. Once with Spot
// as a silhouette forest alone (60 queries) and once with its concave edges as creases (16
// queries: the always-candidate tree of a smooth shape, which competes with the forest's roots).
TEST(QuadricTraversal, EveryDiscontinuityEdgeHasProbabilityAndTheySumToAtMostOne) {
  for (CreaseSet creases : {CreaseSet::None, CreaseSet::Concave}) {
    const auto w = make_world(creases);
    const bool with_creases = creases != CreaseSet::None;
    const auto qs = queries(*w, with_creases ? 16 : 60, with_creases ? 5 : 7);
    for (NodeTest m : {NodeTest::DualBoxAndQuadrics, NodeTest::DualBox}) {
      int missing = 0, over = 0, edges = 0, crease_edges = 0;
      for (const SilhouetteQuery& q : qs) {
        double sum = 0;
        auto check = [&](const Edge& e) {
          const double pr = silhouette_edge_probability(w->forest, q, &e, m);
          sum += pr;
          if (!is_discontinuity(e, q.p)) return;
          ++edges;
          crease_edges += e.crease;
          missing += !(pr > 0);
        };
        for (const Edge& e : w->forest.edges()) check(e);
        for (const Edge& e : w->forest.always_edges()) check(e);
        over += sum > 1 + 1e-9;
      }
      const std::string what = std::string(m == NodeTest::DualBox ? "dual box" : "dual box + quadrics") + (with_creases ? " with creases" : "");
      EXPECT_GT(edges, 1000) << what << ": too few discontinuity edges for power";
      if (with_creases) {
        EXPECT_GT(crease_edges, 16 * 2000) << what << ": too few creases for power";
      }
      EXPECT_EQ(missing, 0) << what << ": discontinuity edges with probability 0";
      EXPECT_EQ(over, 0) << what << ": probabilities summing to more than 1";
    }
  }
}

}  // namespace
}  // namespace qsil::edgetree
