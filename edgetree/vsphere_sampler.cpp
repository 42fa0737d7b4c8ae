/// @file vsphere_sampler.cpp
/// See vsphere_sampler.h.

#include "qsil/edgetree/vsphere_sampler.h"

#include "qsil/check.h"

#include "discrete_choice.h"
#include "edge_point_sampler.h"
#include "qsil/edgetree/ltc.h"

#include <algorithm>
#include <cmath>

namespace qsil::edgetree {

namespace {

bool contains(const Box3& b, const Vec3& p) {
  return !b.empty() && (p.array() >= b.lo.array()).all() && (p.array() <= b.hi.array()).all();
}

/// Largest z of the unit directions on the great arc from a to b (unit vectors).
double arc_max_z(const Vec3& a, const Vec3& b) {
  double m = std::max(a.z(), b.z());
  const Vec3 n = a.cross(b);
  const double nn = n.norm();
  if (!(nn > 0)) return m;
  const Vec3 nu = n / nn;
  Vec3 c = Vec3(0, 0, 1) - nu.z() * nu;  // z projected onto the arc's plane
  const double cn = c.norm();
  if (!(cn > 0)) return m;
  c /= cn;
  if (a.cross(c).dot(n) >= 0 && c.cross(b).dot(n) >= 0) m = std::max(m, c.z());
  return m;
}

}  // namespace

double vsphere_max_bsdf(const Box3& box, const Vec3& p, const Frame& frame, const LTC& ltc) {
  if (!(ltc.norm > 0)) return 0;
  const BoxSilhouette sil = box_silhouette_polygon(box, p);
  if (sil.inside) return ltc.norm * kInvPi;
  SmallPolygon poly;
  if (sil.polygon.count >= 1) {
    for (int i = 0; i < sil.polygon.count; ++i) poly.push(sil.polygon.v[size_t(i)]);
  } else {
    for (int i = 0; i < 8; ++i)
      poly.push(
          Vec3(i & 1 ? box.hi.x() : box.lo.x(), i & 2 ? box.hi.y() : box.lo.y(), i & 4 ? box.hi.z() : box.lo.z()) - p);
  }
  // Directions in the LTC's cosine domain (M_inv of the local direction, normalised).
  std::array<Vec3, kMaxPolygonVertices + 2> u;
  int k = 0;
  for (int i = 0; i < poly.count; ++i) {
    const Vec3 w = ltc.M_inv * frame.to_local(poly.v[size_t(i)]);
    const double n = w.norm();
    if (n > 0) u[size_t(k++)] = w / n;
  }
  if (k == 0) return ltc.norm * kInvPi;  // p on the box's corners only: no bound
  double cmax = -1;
  for (int i = 0; i < k; ++i) cmax = std::max(cmax, u[size_t(i)].z());
  if (k >= 3) {
    // Is the z axis inside the (convex, transformed) outline? Same turn sign for every edge.
    bool pos = true, neg = true;
    for (int i = 0; i < k; ++i) {
      const double s = u[size_t(i)].cross(u[size_t((i + 1) % k)]).z();
      pos = pos && s >= 0;
      neg = neg && s <= 0;
    }
    bool front = false;
    for (int i = 0; i < k; ++i) front = front || u[size_t(i)].z() > 0;
    if ((pos || neg) && front) return ltc.norm * kInvPi;
    for (int i = 0; i < k; ++i) cmax = std::max(cmax, arc_max_z(u[size_t(i)], u[size_t((i + 1) % k)]));
  } else if (k == 2) {
    cmax = std::max(cmax, arc_max_z(u[0], u[1]));
  }
  return ltc.norm * kInvPi * std::clamp(cmax, 0.0, 1.0);
}

namespace {

/// The weights of a child (node box bp, weighted length lw) for the query (vsphere_sampler.h).
void weigh(const Box3& bp, double lw, const SilhouetteQuery& q, bool parent_contains_p, double& importance,
           double& defensive) {
  const double H = (bp.center() - q.p).norm();
  const double diag = bp.diagonal();
  const double h2 = std::max(H * H, 0.25 * diag * diag);
  defensive = h2 > 0 ? lw / h2 : lw;
  if (parent_contains_p) {
    importance = 1.0;
    return;
  }
  const double fmax = vsphere_max_bsdf(bp, q.p, q.frame, q.ltc);
  const double denom = std::max(H, 1e-3 * diag);
  importance = denom > 0 ? lw * fmax / denom : lw * fmax;
}

/// The choice probabilities of candidates (defensive_probabilities, discrete_choice.h).
template <class C>
void mix(const C* c, int n, double* prob) {
  defensive_probabilities(
      c, n, [](const C& x) { return x.importance; }, [](const C& x) { return x.defensive; }, prob);
}

}  // namespace

VSphereEdgeSampler::VSphereEdgeSampler(const EdgeSet& edges, const Vec3& hough_origin, VSphereTest test)
    : edges_(edges), tree_(VSphereTree::build(edges, hough_origin)), test_(test) {
}

int VSphereEdgeSampler::top_candidates(const SilhouetteQuery& q, std::vector<Cand>& out, int& tests) const {
  out.clear();
  for (const VSphereRoot& r : tree_.roots()) {
    if (!q.is_eligible(r.shape)) continue;
    if (r.hough) {
      ++tests;
      if (!tree_.may_have_silhouette(r.node, q.p, test_)) continue;
    }
    Cand c;
    c.node = r.node;
    const VSphereNode& n = tree_.node(r.node);
    weigh(n.bp, n.lw, q, false, c.importance, c.defensive);
    out.push_back(c);
  }
  for (const Edge& e : edges_.always_edges()) {
    if (e.crease || e.crossing || !q.is_eligible(e.shape)) continue;  // in the tree's plain BVH
    Cand c;
    c.edge = &e;
    Box3 b;
    b.expand(e.p0);
    b.expand(e.p1);
    weigh(b, e.length * kPi, q, false, c.importance, c.defensive);
    out.push_back(c);
  }
  return int(out.size());
}

int VSphereEdgeSampler::child_candidates(int n, const SilhouetteQuery& q, Cand* out, int& tests) const {
  const VSphereNode& node = tree_.node(n);
  const bool inside = contains(node.bp, q.p);
  int k = 0;
  for (int c : node.child) {
    const VSphereNode& ch = tree_.node(c);
    if (ch.hough) {
      ++tests;
      if (!tree_.may_have_silhouette(c, q.p, test_)) continue;
    }
    out[k].node = c;
    out[k].edge = nullptr;
    weigh(ch.bp, ch.lw, q, inside, out[k].importance, out[k].defensive);
    ++k;
  }
  return k;
}

/// The buffers of a traversal's top level (EdgeChoiceScratch).
struct VSphereEdgeSampler::Buffers {
  std::vector<Cand> top;
  std::vector<double> prob;
};

SilhouetteSample VSphereEdgeSampler::sample(const SilhouetteQuery& query, const std::function<double()>& next) const {
  SilhouetteSample s;
  EdgeChoiceScratch fallback;
  Buffers& buffers = scratch_buffer<Buffers>(query.scratch, fallback);
  std::vector<Cand>& top = buffers.top;
  std::vector<double>& prob = buffers.prob;
  const int n_top = top_candidates(query, top, s.rejection_tests);
  if (n_top == 0) return s;
  prob.resize(size_t(n_top));
  mix(top.data(), n_top, prob.data());
  int i = choose(prob.data(), n_top, next());
  double pmf = prob[size_t(i)];
  Cand cur = top[size_t(i)];
  // ---- Descend the binary tree to a leaf (one edge).
  while (!cur.edge) {
    const VSphereNode& node = tree_.node(cur.node);
    if (node.is_leaf()) {
      cur.edge = tree_.edges()[size_t(node.edge)];
      break;
    }
    Cand c[2];
    const int k = child_candidates(cur.node, query, c, s.rejection_tests);
    if (k == 0) return s;  // both children rejected: a zero-contribution traversal
    double p2[2];
    mix(c, k, p2);
    i = choose(p2, k, next());
    pmf *= p2[i];
    cur = c[i];
  }
  // ---- Leaves are not tested exactly (Li's method): a non-silhouette is a zero sample (no
  // edge from sample_on_edge).
  return sample_on_edge(*cur.edge, pmf, query, next(), s.rejection_tests);
}

std::vector<EdgeProbability> VSphereEdgeSampler::edge_probabilities(const SilhouetteQuery& query) const {
  std::vector<EdgeProbability> out;
  std::vector<Cand> top;
  int tests = 0;
  const int n_top = top_candidates(query, top, tests);
  if (n_top == 0) return out;
  std::vector<double> prob(static_cast<size_t>(n_top));
  mix(top.data(), n_top, prob.data());
  std::vector<std::pair<int, double>> stack;
  for (int i = 0; i < n_top; ++i) {
    if (!(prob[size_t(i)] > 0)) continue;
    if (top[size_t(i)].edge)
      out.push_back({top[size_t(i)].edge, prob[size_t(i)]});
    else
      stack.emplace_back(top[size_t(i)].node, prob[size_t(i)]);
  }
  while (!stack.empty()) {
    const auto [n, pn] = stack.back();
    stack.pop_back();
    const VSphereNode& node = tree_.node(n);
    if (node.is_leaf()) {
      out.push_back({tree_.edges()[size_t(node.edge)], pn});
      continue;
    }
    Cand c[2];
    const int k = child_candidates(n, query, c, tests);
    double p2[2];
    mix(c, k, p2);
    for (int j = 0; j < k; ++j)
      if (p2[j] > 0) stack.emplace_back(c[j].node, pn * p2[j]);
  }
  return out;
}

}  // namespace qsil::edgetree
