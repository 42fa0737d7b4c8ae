/// @file baseline_pdf_test.cpp
/// The discrete part of the baseline samplers' pdfs (vsphere, vsphere-solid, uniform), for random
/// shading points, frames and BSDF LTCs on a three-shape forest (spot, a subdivided cube, an open
/// square sheet whose outline is always-candidate):
/// - the probabilities of all edges (exhaustive traversal, edge_probabilities) sum to <= 1;
/// - every silhouette edge of an eligible shape has probability > 0 (unbiasedness); edges of
///   ineligible shapes have none;
/// - the histogram of sample() matches: chi-square (Mitsuba's pooling) at 1% family
///   significance (Šidák over all cases), bins = silhouette edges + one "no edge" bin;
/// - the returned pdf equals probability x EdgePointSampler::pdf(t) (relative 1e-9).
/// Fixed seeds.

#include "baselines/baseline_test_util.h"
#include "chi2.h"
#include "edgetree/edge_point_sampler.h"
#include "qsil/edgetree/edge_forest.h"
#include "qsil/edgetree/ltc.h"
#include "qsil/edgetree/uniform_sampler.h"
#include "qsil/edgetree/vsphere_sampler.h"
#include "qsil/rng.h"

#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <random>

namespace qsil::edgetree {
namespace {

using namespace qsil::baselines_test;
using namespace qsil::test;

struct World {
  std::vector<TriangleMesh> meshes;
  EdgeForest forest;
};

std::unique_ptr<World> make_world() {
  auto w = std::make_unique<World>();
  w->meshes.push_back(test_mesh("spot.obj"));
  TriangleMesh cube = make_cube(3);
  for (auto& p : cube.positions) p = 0.3 * p + Vec3(1.2, 0.2, -0.3);
  w->meshes.push_back(cube);
  TriangleMesh sheet;
  sheet.positions = {{-1, -0.8, -1}, {1, -0.8, -1}, {1, -0.8, 1}, {-1, -0.8, 1}};
  sheet.triangles = {{0, 2, 1}, {0, 3, 2}};
  w->meshes.push_back(sheet);
  w->forest = forest_over(w->meshes);
  return w;
}

struct TestedSampler {
  std::string name;
  std::unique_ptr<EdgeSampler> sampler;
  std::function<std::vector<EdgeProbability>(const SilhouetteQuery&)> probabilities;
};

std::vector<TestedSampler> methods(const EdgeSet& f, const Vec3& o) {
  std::vector<TestedSampler> m;
  for (VSphereTest t : {VSphereTest::Hollow, VSphereTest::Solid}) {
    auto s = std::make_unique<VSphereEdgeSampler>(f, o, t);
    const VSphereEdgeSampler* raw = s.get();
    m.push_back({std::string(s->name()), std::move(s),
                 [raw](const SilhouetteQuery& q) { return raw->edge_probabilities(q); }});
  }
  auto u = std::make_unique<UniformEdgeSampler>(f);
  const UniformEdgeSampler* raw = u.get();
  m.push_back({"uniform", std::move(u), [raw](const SilhouetteQuery& q) { return raw->edge_probabilities(q); }});
  return m;
}

/// Random queries: points of the soundness set around spot, random normals, diffuse or GGX LTCs,
/// all shapes or a subset eligible.
struct QueryCase {
  SilhouetteQuery q;
  std::vector<bool> eligible;
};

std::vector<QueryCase> queries(const World& w, int n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g;
  std::uniform_real_distribution<double> u(0, 1);
  const std::vector<Vec3> pts = shading_points(w.meshes[0], n, seed);
  std::vector<QueryCase> out(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    QueryCase& c = out[i];
    c.q.p = pts[i];
    c.q.frame = Frame(Vec3(g(rng), g(rng), g(rng)).normalized());
    if (i % 2) {
      c.q.ltc = ltc_diffuse();
      c.q.ltc.norm = 0.7;
    } else {
      c.q.ltc = ltc_ggx(std::pow(10.0, -2.5 + 2.5 * u(rng)), Vec3(g(rng), g(rng), std::abs(g(rng)) + 0.1).normalized());
    }
    c.eligible = i % 3 == 0 ? std::vector<bool>{true, false, true} : std::vector<bool>{true, true, true};
  }
  for (auto& c : out) c.q.eligible = &c.eligible;
  return out;
}

TEST(BaselinePdf, SumsToAtMostOneAndEverySilhouetteHasProbability) {
  const auto w = make_world();
  const Vec3 o = camera_like_origin(w->meshes[0]);
  auto ms = methods(w->forest, o);
  auto qs = queries(*w, 150, 31);
  for (const TestedSampler& m : ms) {
    int missing = 0, ineligible = 0, over = 0;
    for (const QueryCase& c : qs) {
      const auto probs = m.probabilities(c.q);
      std::map<const Edge*, double> pm;
      double sum = 0;
      for (const auto& e : probs) {
        pm[e.edge] += e.probability;
        sum += e.probability;
        ineligible += !c.eligible[size_t(e.edge->shape)];
      }
      over += sum > 1 + 1e-12;
      auto check = [&](const Edge& e) {
        if (c.eligible[size_t(e.shape)] && edge_is_silhouette(e, c.q.p) && !(pm[&e] > 0)) ++missing;
      };
      for (const Edge& e : w->forest.edges()) check(e);
      for (const Edge& e : w->forest.always_edges()) check(e);
    }
    EXPECT_EQ(missing, 0) << m.name << ": silhouette edges with probability 0";
    EXPECT_EQ(ineligible, 0) << m.name << ": edges of ineligible shapes with probability > 0";
    EXPECT_EQ(over, 0) << m.name << ": probabilities summing to more than 1";
  }
}

TEST(BaselinePdf, HistogramMatchesProbabilities) {
  const auto w = make_world();
  const Vec3 o = camera_like_origin(w->meshes[0]);
  auto ms = methods(w->forest, o);
  auto qs = queries(*w, 6, 32);
  const int n = 40000;
  const double alpha = sidak(0.01, int(ms.size() * qs.size()));
  for (const TestedSampler& m : ms) {
    for (size_t qi = 0; qi < qs.size(); ++qi) {
      const QueryCase& c = qs[qi];
      const auto probs = m.probabilities(c.q);
      std::map<const Edge*, int> bin;
      std::vector<double> expected(1, 0.0);  // bin 0: no edge (or a non-silhouette)
      double sil_mass = 0;
      for (const auto& e : probs) {
        if (!edge_is_silhouette(*e.edge, c.q.p)) continue;
        bin[e.edge] = int(expected.size());
        expected.push_back(n * e.probability);
        sil_mass += e.probability;
      }
      expected[0] = n * std::max(0.0, 1.0 - sil_mass);
      std::vector<double> observed(expected.size(), 0.0);
      Sampler rng(77, qi, 0);
      int bad_pdf = 0, unknown = 0;
      for (int i = 0; i < n; ++i) {
        const SilhouetteSample s = m.sampler->sample(c.q, [&] { return rng.next(); });
        if (!s.edge) {
          observed[0] += 1;
          continue;
        }
        auto it = bin.find(s.edge);
        if (it == bin.end()) {
          ++unknown;
          continue;
        }
        observed[size_t(it->second)] += 1;
        const EdgePointSampler ps(c.q.frame.to_local(s.edge->p0 - c.q.p), c.q.frame.to_local(s.edge->p1 - c.q.p),
                                  c.q.ltc);
        const double want = expected[size_t(it->second)] / n * ps.pdf(s.t);
        bad_pdf += !(std::abs(s.pdf - want) <= 1e-9 * want);
      }
      EXPECT_EQ(unknown, 0) << m.name << " query " << qi << ": sampled an edge of probability 0";
      EXPECT_EQ(bad_pdf, 0) << m.name << " query " << qi << ": pdf != probability x pdf(t)";
      const Chi2Result r = chi2_test(observed, expected, alpha);
      EXPECT_TRUE(r.passed) << m.name << " query " << qi << ": " << r.message;
    }
  }
}

}  // namespace
}  // namespace qsil::edgetree
