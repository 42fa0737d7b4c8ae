/// @file silhouette_sampler.cpp
/// See silhouette_sampler.h.

#include "qsil/edgetree/silhouette_sampler.h"

#include "discrete_choice.h"
#include "edge_mixture.h"
#include "positive_part.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <span>

namespace qsil::edgetree {

namespace {

/// One candidate of a choice: a node (index >= 0) or an edge, with its weights.
struct Candidate {
  int node = -1;
  const Edge* edge = nullptr;
  NodeWeight w;
};

/// Probabilities of a choice among candidates (see the file comment of the header).
template <class Range>
void choice_probabilities(const Range& c, int n, double* prob) {
  defensive_probabilities(
      c, n, [](const Candidate& x) { return x.w.importance; }, [](const Candidate& x) { return x.w.defensive; }, prob);
}

/// G_e = length / d2, d2 the squared distance of the edge's midpoint from p (length where p is at
/// the midpoint).
double edge_defensive(double length, double d2) { return d2 > 0 ? length / d2 : length; }

/// Inner nodes of the quadric method with at most this many edges are tested edge by edge
/// (node_has_silhouette) instead of by their bound: exact (no false accept, so no traversal dies
/// in a subtree without silhouettes) and, at this size, cheaper than the bound's polygon and conic
/// tests. QuadricBox keeps the bound alone (the paper's ablation). Measured in the issue note.
constexpr int kExactTestEdges = 64;

/// Inner nodes of the quadric method with at most this many edges choose among all their
/// discontinuity edges at once (flat_candidates), each weighed as a leaf weighs its edges,
/// instead of descending through their children by box importance (see the header): the size
/// below which the forest is handled edge by edge.
constexpr int kFlatEdges = kExactTestEdges;

struct ForestBuffers;

/// A query with its per-query constants: the lights that face p, in the local frame; and the
/// buffers of its traversal (from q.scratch, or from the caller's own scratch).
struct PreparedQuery {
  const SilhouetteQuery& q;
  std::span<const LocalLight> lights;
  bool cosine_lobe;  ///< q.ltc is the clamped cosine (M_inv = I): far boxes use cone_fbar, far edges far_total
  ForestBuffers& buffers;
  /// The guide's values in the cell of q.p (ForestGuide::cell_values), or null: unguided.
  const double* guide_values = nullptr;
  /// The query's map into the LTC's cosine domain (edge importances, EdgeMixture::total).
  LtcMap ltc_map;
};

/// The query's constants, in buffers of q.scratch, or of `fallback` where q has none.
PreparedQuery prepare(const SilhouetteQuery& q, EdgeChoiceScratch& fallback);

NodeWeight node_weight(const ForestNode& node, const PreparedQuery& prepared);
NodeWeight leaf_edge_weight(const Edge& e, const PreparedQuery& prepared);
NodeWeight loose_edge_weight(const Edge& e, const PreparedQuery& prepared);

/// Whether node n may lead to a silhouette for the query (the test of a non-always node).
bool accepted(const EdgeForest& f, int n, const SilhouetteQuery& q, NodeTest test) {
  const ForestNode& node = f.node(n);
  if (test == NodeTest::DualBoxAndQuadrics && !node.is_leaf() && node.edge_end - node.edge_begin <= kExactTestEdges)
    return node_has_silhouette(f, n, q.p);
  return may_have_silhouette(f, n, q.p, test);
}

/// The candidates at the top level: accepted, eligible forest roots, the roots of the
/// always-candidate trees (never rejected) and the loose always-candidate edges.
int top_candidates(const EdgeForest& f, const PreparedQuery& prepared, NodeTest test, std::vector<Candidate>& out, int& tests) {
  const SilhouetteQuery& q = prepared.q;
  out.clear();
  for (int r : f.roots()) {
    if (!q.is_eligible(f.node(r).shape)) continue;
    ++tests;
    if (!accepted(f, r, q, test)) continue;
    out.push_back({r, nullptr, node_weight(f.node(r), prepared)});
  }
  for (int r : f.always_roots())
    if (q.is_eligible(f.node(r).shape)) out.push_back({r, nullptr, node_weight(f.node(r), prepared)});
  for (int i : f.loose_always_edges()) {
    const Edge& e = f.always_edges()[size_t(i)];
    if (!q.is_eligible(e.shape)) continue;
    out.push_back({-1, &e, loose_edge_weight(e, prepared)});
  }
  return int(out.size());
}

/// The accepted children of inner node `n` (up to 4). Weighed only when there are two or more:
/// a single candidate is chosen with probability 1 whatever its weights (choice_probabilities
/// gives exactly 1 for n = 1), and 17 % of the inner choices and 56 % of the leaf choices on
/// spot-mirror have one candidate.
int child_candidates(const EdgeForest& f, int n, const PreparedQuery& prepared, NodeTest test, std::array<Candidate, 4>& out,
                     int& tests) {
  int k = 0;
  const ForestNode& node = f.node(n);
  for (int c = node.first; c < node.first + node.count; ++c) {
    if (!f.node(c).always()) {  // always-candidate trees have no rejection test
      ++tests;
      if (!accepted(f, c, prepared.q, test)) continue;
    }
    out[k++] = {c, nullptr, {}};
  }
  if (k > 1)
    for (int i = 0; i < k; ++i) out[size_t(i)].w = node_weight(f.node(out[size_t(i)].node), prepared);
  return k;
}

/// The silhouette edges of leaf `n` (exact per-edge test; up to 4), weighed when two or more.
int leaf_candidates(const EdgeForest& f, int n, const PreparedQuery& prepared, std::array<Candidate, 4>& out) {
  int k = 0;
  for (const Edge& e : f.leaf_edges(n))
    if (is_discontinuity(e, prepared.q.p)) out[k++] = {-1, &e, {}};
  if (k > 1)
    for (int i = 0; i < k; ++i) out[size_t(i)].w = leaf_edge_weight(*out[size_t(i)].edge, prepared);
  return k;
}

/// Inner nodes of the quadric method with at most this many edges whose box's bounding sphere
/// contains the query point choose flat too (see the header, "Near field").
constexpr int kNearFlatEdges = 1024;

/// Whether the traversal chooses an edge of node `node` directly (flat_candidates) for a query
/// at p.
bool is_flat(const ForestNode& node, NodeTest test, const Vec3& p) {
  if (test != NodeTest::DualBoxAndQuadrics || node.is_leaf()) return false;
  const int edges = node.edge_end - node.edge_begin;
  if (edges <= kFlatEdges) return true;
  if (edges > kNearFlatEdges) return false;
  const double r = 0.5 * node.bp.diagonal();
  return (node.bp.center() - p).squaredNorm() < r * r;
}

/// The discontinuity edges below node `n` (at most kNearFlatEdges), weighed as a leaf's when two or
/// more, with their choice probabilities in `prob`. Returns their count (0: none, a false accept).
int flat_candidates(const EdgeForest& f, int n, const PreparedQuery& prepared, std::vector<Candidate>& out,
                    std::vector<double>& prob) {
  out.clear();
  for (const Edge& e : f.node_edges(n))
    if (is_discontinuity(e, prepared.q.p)) out.push_back({-1, &e, {}});
  const int k = int(out.size());
  prob.resize(size_t(std::max(k, 1)));
  if (k == 1) prob[0] = 1.0;
  if (k > 1) {
    for (Candidate& c : out) c.w = leaf_edge_weight(*c.edge, prepared);
    choice_probabilities(out, k, prob.data());
  }
  return k;
}

/// The probabilities of a choice among the k candidates of one level (1 for a single one).
void level_probabilities(const std::array<Candidate, 4>& cand, int k, std::array<double, 4>& prob) {
  if (k == 1)
    prob[0] = 1.0;
  else
    choice_probabilities(cand, k, prob.data());
}

/// The guided slot of candidate c (ForestGuide): a node's, or a loose always-candidate edge's;
/// -1 for any other candidate or without a guide.
int candidate_slot(const EdgeForest& f, const PreparedQuery& prepared, const Candidate& c) {
  const ForestGuide* g = prepared.q.guide;
  if (!g) return -1;
  if (!c.edge) return g->node_slot(c.node);
  const std::vector<Edge>& always = f.always_edges();
  if (always.empty() || c.edge < always.data() || c.edge >= always.data() + always.size()) return -1;
  return g->loose_edge_slot(int(c.edge - always.data()));
}

/// The guided strategy's probabilities gprob[0..k) of a choice among candidates cand[0..k) whose
/// unguided probabilities are prob[0..k): the guide's (ForestGuide::guided) where every candidate
/// is a guided slot and the cell learnt something of them, else prob's. Returns whether the
/// choice is a guided one (a guide, k >= 2, every candidate a slot; learnt or not): the choices
/// a sample's training records are made of.
template <class Range>
bool guide_choice(const EdgeForest& f, const PreparedQuery& prepared, const Range& cand, int k, const double* prob,
                  double* gprob, std::vector<int>& slots) {
  std::copy(prob, prob + k, gprob);
  if (!prepared.q.guide || k < 2) return false;
  slots.resize(size_t(k));
  for (int i = 0; i < k; ++i) {
    slots[size_t(i)] = candidate_slot(f, prepared, cand[size_t(i)]);
    if (slots[size_t(i)] < 0) return false;
  }
  if (prepared.guide_values) prepared.q.guide->guided(prepared.guide_values, slots.data(), k, prob, gprob);
  return true;
}

/// The guided choices of one traversal (SilhouetteSample::guide_slots, guide_pu).
struct GuideTrail {
  std::array<int, kMaxGuideLevels> slots{};
  std::array<double, kMaxGuideLevels> pu{};
  int levels = 0;
  void add(int slot, double p) {
    if (levels == kMaxGuideLevels) return;
    slots[size_t(levels)] = slot;
    pu[size_t(levels++)] = p;
  }
};

/// The probability of a choice of path through the forest: the unguided strategy's product pu and
/// the guided strategy's pg, mixed (ForestGuide: the defensive share s of the unguided strategy)
/// as s pu + (1 - s) pg; pu alone without a guide in the query's cell.
struct PathProbability {
  double pu = 1, pg = 1;
  double mixed(const PreparedQuery& prepared) const {
    if (!prepared.guide_values) return pu;
    const double share = prepared.q.guide->share();
    return share * pu + (1 - share) * pg;
  }
};

SilhouetteSample sample_on_edge(const Edge& e, double pmf, const PreparedQuery& prepared, double u, int rejection_tests);

}  // namespace

namespace {

/// velocity_factor from the edge's geometry relative to p (shared with its far_total).
double velocity_factor(const Edge& e, const SilhouetteQuery& q, const EdgeGeometry& g) {
  if (!q.velocities) return 1.0;
  if (!(g.normal_len > 0)) return 0.0;  // p on the edge's line: no plane, J = 0
  auto factor = [&](const SceneVelocities::Block& v0, const SceneVelocities::Block& v1) {
    double f = 0;
    for (int k = 0; k < q.velocities->num_params; ++k) {
      const double n_dp = g.normal.dot(q.dp.col(k));
      f += 0.5 * (std::abs(g.normal.dot(v0.col(k)) - n_dp) + std::abs(g.normal.dot(v1.col(k)) - n_dp)) *
           q.velocity_scale[size_t(k)];
    }
    return f / g.normal_len;
  };
  // A mesh edge's end velocities by reference (a Block is 3 x kMaxParameters doubles, and this runs
  // for every weighed candidate edge), a crossing's computed.
  if (e.crossing) return factor(edge_end_velocity(e, 0, *q.velocities), edge_end_velocity(e, 1, *q.velocities));
  return factor(mesh_edge_end_velocity(e, 0, *q.velocities), mesh_edge_end_velocity(e, 1, *q.velocities));
}

}  // namespace

double velocity_factor(const Edge& e, const SilhouetteQuery& q) {
  return velocity_factor(e, q, EdgeGeometry(e, q.p));
}

bool light_billboard(const LightSphere& light, const Vec3& p, LightPolygon& out) {
  const Vec3 to_centre = light.centre - p;
  const double d2 = to_centre.squaredNorm(), r2 = light.radius * light.radius;
  if (!(light.weight > 0) || !(d2 > r2)) return false;
  const double d = std::sqrt(d2);
  const Vec3 a = to_centre / d;
  // D tan(beta) = D r / sqrt(D^2 - r^2).
  const double half = d * light.radius / std::sqrt(d2 - r2);
  if (!std::isfinite(half)) return false;
  const Vec3 s = a.unitOrthogonal() * half, t = a.cross(a.unitOrthogonal()) * half;
  out.corners = {light.centre - s - t, light.centre + s - t, light.centre + s + t, light.centre - s + t};
  out.normal = -a;
  out.weight = light.weight;
  out.shape = light.shape;
  return true;
}

double enclosing_light_weight(const std::vector<LightSphere>* spheres, const Vec3& p) {
  double w = 0;
  if (spheres)
    for (const LightSphere& l : *spheres)
      if (l.weight > 0 && (l.centre - p).squaredNorm() <= l.radius * l.radius) w += l.weight;
  return w;
}

namespace {

/// Appends `light` seen from q.p to `out` when it emits toward q.p (light_toward).
void push_local_light(const LightPolygon& light, const SilhouetteQuery& q, std::vector<LocalLight>& out) {
  LocalLight l;
  if (!light_toward(light, q, l.corners)) return;
  const Vec3 inside = l.corners[0] + l.corners[1] + l.corners[2] + l.corners[3];
  for (int i = 0; i < 4; ++i) {
    Vec3 n = l.corners[size_t(i)].cross(l.corners[size_t((i + 1) % 4)]);
    if (n.dot(inside) < 0) n = -n;
    const double len = n.norm();
    l.sides[size_t(i)] = len > 0 ? Vec3(n / len) : Vec3::Zero();
    l.sides_world[size_t(i)] = q.frame.to_world(l.sides[size_t(i)]);
  }
  l.weight = light.weight;
  out.push_back(l);
}

}  // namespace

void local_lights(const SilhouetteQuery& q, std::vector<LocalLight>& out) {
  out.clear();
  for_each_light_quad(q, [&](const LightPolygon& light) { push_local_light(light, q, out); });
}

NodeWeight leaf_edge_weight(const Edge& e, const SilhouetteQuery& q) {
  EdgeChoiceScratch fallback;
  return leaf_edge_weight(e, prepare(q, fallback));
}

NodeWeight loose_edge_weight(const Edge& e, const SilhouetteQuery& q) {
  EdgeChoiceScratch fallback;
  return loose_edge_weight(e, prepare(q, fallback));
}

NodeWeight node_weight(const ForestNode& node, const SilhouetteQuery& q) {
  EdgeChoiceScratch fallback;
  return node_weight(node, prepare(q, fallback));
}

namespace {

/// kSmoothCreaseWeight where it applies (see the header): a smooth crease that is no silhouette
/// for p, under the cosine lobe.
double crease_factor(const Edge& e, const PreparedQuery& prepared) {
  return prepared.cosine_lobe && e.smooth_crease && !edge_is_silhouette(e, prepared.q.p) ? kSmoothCreaseWeight : 1.0;
}

NodeWeight leaf_edge_weight(const Edge& e, const PreparedQuery& prepared) {
  const SilhouetteQuery& q = prepared.q;
  const EdgeGeometry g(e, q.p);  // once for the importance, its velocity factor and the defensive weight
  const double half = 0.5 * e.length;
  const bool far = prepared.cosine_lobe && half * half < kConeImportanceSin * kConeImportanceSin * g.mid2;
  const double total = far ? EdgeMixture::far_total(e, q, prepared.lights, g)
                           : EdgeMixture::total(e, q, prepared.lights, prepared.ltc_map, g);
  // velocity_factor is finite, so a zero total needs no factor (below the horizon, outside every light).
  const double c = crease_factor(e, prepared);
  return {total > 0 ? c * total * velocity_factor(e, q, g) : 0.0, c * edge_defensive(e.length, g.mid2)};
}

NodeWeight loose_edge_weight(const Edge& e, const PreparedQuery& prepared) {
  const double c = kPi * crease_factor(e, prepared);
  const EdgeGeometry g(e, prepared.q.p);
  return {c * EdgeMixture::total(e, prepared.q, prepared.lights, prepared.ltc_map, g),
          c * edge_defensive(e.length, g.mid2)};
}

/// The range [lo, hi] of n . w over the cone of unit directions w at angle at most alpha from a
/// unit axis, where x = n . axis (n unit) and s, co = sin alpha, cos alpha: the angle between n
/// and w spans [theta - alpha, theta + alpha] clamped to [0, pi], theta = acos x.
void dot_range(double x, double s, double co, double& lo, double& hi) {
  const double t = std::sqrt(std::max(0.0, 1.0 - x * x));
  hi = x >= co ? 1.0 : x * co + t * s;
  lo = x <= -co ? -1.0 : x * co - t * s;
}

/// The radiance seen over the bounding cone (unit axis, sin and cos of its half-angle s, co): the
/// environment's plus each light's times the fraction of the cone on the inner side of each of
/// its 4 side planes (P(X > 0) with X = side normal . w uniform on its range, multiplied).
double cone_radiance(const PreparedQuery& prepared, const Vec3& axis, double s, double co) {
  double radiance = prepared.q.env_weight;
  for (const LocalLight& light : prepared.lights) {
    double fraction = 1.0;
    for (int i = 0; i < 4 && fraction > 0; ++i) {
      double lo, hi;
      dot_range(light.sides[size_t(i)].dot(axis), s, co, lo, hi);
      fraction *= positive_fraction(lo, hi);
    }
    radiance += light.weight * fraction;
  }
  return radiance;
}

/// fbar of node_weight for a box far from p and the cosine lobe, from the box's bounding cone
/// (axis d = box centre - p, local frame after to_local; sin alpha = s = half diagonal /
/// |d| < 1) instead of its outline: with X = n . w taken as uniform on its range over the cone,
/// the mean of max(0, cos theta)/pi over the cone (E[max(0, X)]/pi for n = z) times the
/// environment's radiance plus each light's times the fraction of the cone on the inner side of
/// each of its 4 side planes (P(X > 0), multiplied). Positive wherever the box's outline can
/// reach above the horizon into the light (the ranges are exact bounds), so it is zero only
/// where the exact fbar is; otherwise an approximation, as an importance may be.
double cone_fbar(const PreparedQuery& prepared, const Vec3& axis, double s) {
  const SilhouetteQuery& q = prepared.q;
  const double co = std::sqrt(1.0 - s * s);
  double lo, hi;
  dot_range(axis.z(), s, co, lo, hi);
  if (!(hi > 0)) return 0.0;
  return q.ltc.norm * mean_positive_part(lo, hi) / kPi * cone_radiance(prepared, axis, s, co);
}

/// Largest |dt|^2 + |db|^2 (see glossy_cone_fbar) for which a cone's image in the LTC's cosine
/// domain is taken as an ellipse: images whose largest radius may reach 90 degrees take the exact
/// integral. Measured (spot-mirror, 128², 8 seeds of 32 spp, the same seeds both ways, against
/// the exact form): 0.5: time -12 %, variance +3 %; 1: -14 %, -6 %; always the cone: -28 %, +33 %.
constexpr double kGlossyConeImage = 1.0;

/// fbar of node_weight for a box far from p and a glossy lobe, from the box's bounding cone
/// (unit axis in the local frame, s = sin of its half-angle, as for cone_fbar), or -1 where the
/// cone's image in the LTC's cosine domain is too wide for the estimate (kGlossyConeImage): then
/// the caller takes the exact integral over the box's outline.
/// The LTC integral over the cone is the Lambert form factor of its image under M_inv ([LTC]
/// Eq. 11); the image of the cone's rim is nearly the spherical ellipse c + cos(phi) dt +
/// sin(phi) db, with dt, db the half chords between the images of two pairs of opposite rim
/// directions (conjugate semi-diameters, exact for a linear map) and c their normalised mean.
/// Its form factor is taken as its area / pi, |dt x db|, times the mean of max(0, z) over it,
/// with z uniform on its range c.z -+ sqrt(dt.z^2 + db.z^2) where the range crosses the horizon
/// (exact for a cap above the horizon), capped at 1; times the fraction of the cone above the
/// shading horizon (as cone_fbar takes it), norm and cone_radiance, divided by the cone's solid
/// angle 2 pi (1 - cos alpha). No outline, clipping or angles. Zero where the cone lies below
/// the shading horizon (exactly, as for cone_fbar) or the ellipse's z range below 0, which is
/// the image's up to the ellipse approximation (node_importance_test found no box with a
/// positive integrand and zero importance; the defensive share of every choice covers any).
double glossy_cone_fbar(const PreparedQuery& prepared, const Vec3& axis, double s) {
  const SilhouetteQuery& q = prepared.q;
  const double co = std::sqrt(1.0 - s * s);
  double lo, hi;
  dot_range(axis.z(), s, co, lo, hi);  // the shading normal over the cone
  if (!(hi > 0)) return 0.0;
  const double above = positive_fraction(lo, hi);
  const Vec3 t = axis.unitOrthogonal(), b = axis.cross(t);
  const Mat3& M = q.ltc.M_inv;
  const Vec3 ma = M * (co * axis), mt = M * (s * t), mb = M * (s * b);
  // Unit vectors by one reciprocal square root each (normalized() divides every component).
  auto unit = [](const Vec3& v) -> Vec3 { return v * (1.0 / std::sqrt(v.squaredNorm())); };
  const Vec3 r0 = unit(ma + mt), r1 = unit(ma - mt), r2 = unit(ma + mb), r3 = unit(ma - mb);
  const Vec3 dt = 0.5 * (r0 - r1), db = 0.5 * (r2 - r3);
  if (!(dt.squaredNorm() + db.squaredNorm() < kGlossyConeImage)) return -1.0;
  const Vec3 sum = r0 + r1 + r2 + r3;
  const double cz = sum.z() / std::sqrt(sum.squaredNorm());
  const double h = std::sqrt(dt.z() * dt.z() + db.z() * db.z());
  if (!(cz + h > 0)) return 0.0;
  const double mass = std::min(1.0, dt.cross(db).norm() * mean_positive_part(cz - h, cz + h));
  const double omega = 2.0 * kPi * s * s / (1.0 + co);  // 2 pi (1 - co) without cancellation
  return q.ltc.norm * above * mass / omega * cone_radiance(prepared, axis, s, co);
}

NodeWeight node_weight(const ForestNode& node, const PreparedQuery& prepared) {
  const SilhouetteQuery& q = prepared.q;
  const Vec3 c = node.bp.center();
  const double half_diag = 0.5 * node.bp.diagonal();
  const double d2 = (c - q.p).squaredNorm();
  const double h2 = std::max(d2, half_diag * half_diag);
  NodeWeight w;
  // L_w with its concave smooth creases' part weighed by kSmoothCreaseWeight under the cosine lobe.
  const double lw = prepared.cosine_lobe ? node.lw - (1.0 - kSmoothCreaseWeight) * node.lw_smooth : node.lw;
  w.defensive = h2 > 0 ? lw / h2 : lw;
  if (half_diag * half_diag < kConeImportanceSin * kConeImportanceSin * d2) {
    const double inv_d = 1.0 / std::sqrt(d2);
    const Vec3 axis = q.frame.to_local((c - q.p) * inv_d);
    const double sin_alpha = half_diag * inv_d;
    const double fbar =
        prepared.cosine_lobe ? cone_fbar(prepared, axis, sin_alpha) : glossy_cone_fbar(prepared, axis, sin_alpha);
    if (fbar >= 0) {
      w.importance = w.defensive * fbar;
      return w;
    }
  }
  const BoxSilhouette sil = box_silhouette_polygon(node.bp, q.p);
  double fbar = 0;
  if (sil.inside) {
    // The box surrounds p: the average over the whole sphere of f_s cos times the radiance: the
    // environment's, and each light's over its own solid angle (its LTC integral; a light can lie
    // anywhere in the box's solid angle).
    double integral = q.env_weight;
    for (const LocalLight& light : prepared.lights)
      integral += light.weight * ltc_polygon_integral(q.ltc, light.corners, true);
    fbar = integral * q.ltc.norm / (4.0 * kPi);
  } else if (sil.polygon.count >= 3) {
    SmallPolygon local;
    for (int i = 0; i < sil.polygon.count; ++i) local.push(q.frame.to_local(sil.polygon.v[size_t(i)]));
    // Fast (approximate) angles: an importance needs consistency, not accuracy.
    const double omega = polygon_solid_angle(local.span(), true);
    if (omega > 0) {
      double integral = q.env_weight > 0 ? q.env_weight * ltc_polygon_integral(q.ltc, local.span(), true) : 0.0;
      for (const LocalLight& light : prepared.lights) {
        // Only the emitting side of a light is bright; clip the box's cone by the light's.
        SmallPolygon clipped = local;
        for (int i = 0; i < 4 && clipped.count >= 3; ++i)
          clipped = clip_polygon_to_halfspace(clipped.span(), light.sides[size_t(i)]);
        if (clipped.count >= 3) integral += light.weight * ltc_polygon_integral(q.ltc, clipped.span(), true);
      }
      fbar = q.ltc.norm * integral / omega;
    }
  }
  w.importance = w.defensive * fbar;
  return w;
}

}  // namespace

namespace {

/// The top level of a traversal: candidates and their probabilities.
struct TopLevel {
  std::vector<Candidate> cand;
  std::vector<double> prob;
  std::vector<double> gprob;  ///< the guided strategy's (guide_choice)
  bool guided = false;        ///< a guided choice (guide_choice)
  int n = 0;
  int tests = 0;
};

/// The buffers of the forest traversal (EdgeChoiceScratch), one set per use.
struct ForestBuffers {
  std::vector<LocalLight> lights;                 ///< prepare
  std::vector<Candidate> rest, flat, contour_cand;  ///< remove_split, descend, sample_contour
  std::vector<int> rest_index;                    ///< remove_split
  std::vector<double> rest_prob, flat_prob, contour_prob;
  TopLevel top_sample, top_set;                   ///< sample_silhouette, sample_silhouette_set
  std::vector<const Edge*> contour;               ///< sample_silhouette_set
  std::vector<int> slots;                         ///< guide_choice
  std::vector<double> rest_gprob;                 ///< remove_split (the guided strategy's)
};

PreparedQuery prepare(const SilhouetteQuery& q, EdgeChoiceScratch& fallback) {
  ForestBuffers& b = scratch_buffer<ForestBuffers>(q.scratch, fallback);
  local_lights(q, b.lights);
  return {q, b.lights, is_cosine_lobe(q.ltc), b, q.guide ? q.guide->cell_values(q.p) : nullptr, LtcMap(q)};
}

void top_level(const EdgeForest& forest, const PreparedQuery& prepared, NodeTest test, TopLevel& top) {
  top.tests = 0;
  top.n = top_candidates(forest, prepared, test, top.cand, top.tests);
  top.prob.resize(size_t(std::max(top.n, 1)));
  if (top.n > 0) choice_probabilities(top.cand, top.n, top.prob.data());
  top.gprob.resize(top.prob.size());
  top.guided =
      guide_choice(forest, prepared, top.cand, top.n, top.prob.data(), top.gprob.data(), prepared.buffers.slots);
}

/// Indices (into top.cand) of the split edges: loose edges with probability >= kSplitShare, the
/// kMaxSplitEdges most probable (ties: the first). Returns their count.
int split_indices(const TopLevel& top, std::array<int, kMaxSplitEdges>& idx) {
  int k = 0;
  for (int i = 0; i < top.n; ++i) {
    if (!top.cand[size_t(i)].edge || !(top.prob[size_t(i)] >= kSplitShare)) continue;
    if (k < kMaxSplitEdges) {
      idx[size_t(k++)] = i;
    } else {  // replace the least probable when i is more probable
      int worst = 0;
      for (int j = 1; j < k; ++j)
        if (top.prob[size_t(idx[size_t(j)])] < top.prob[size_t(idx[size_t(worst)])]) worst = j;
      if (top.prob[size_t(i)] > top.prob[size_t(idx[size_t(worst)])]) idx[size_t(worst)] = i;
    }
  }
  return k;
}

/// Takes the split edges idx[0..n_split) out of the top-level choice: they get probability 0 and
/// the traversal chooses among the other candidates afresh (choice_probabilities over them alone:
/// importance and defensive weights both normalised over the rest, the defensive share eps as at
/// every choice). Dividing the old probabilities by 1 - (the split sum) instead kept the defensive
/// part at its old size while the split edges had taken most of the importance part: on the
/// teapot's self-shadows the rest's choice was then up to ~40 % defensive (docs/architecture.md §5
/// "Splitting"). Returns false when no candidate is left.
bool remove_split(const EdgeForest& forest, const PreparedQuery& prepared, TopLevel& top,
                  const std::array<int, kMaxSplitEdges>& idx, int n_split) {
  ForestBuffers& b = prepared.buffers;
  auto is_split = [&](int i) { return std::find(idx.begin(), idx.begin() + n_split, i) != idx.begin() + n_split; };
  std::vector<Candidate>& rest = b.rest;
  std::vector<int>& where = b.rest_index;
  std::vector<double>& prob = b.rest_prob;
  rest.clear();
  where.clear();
  for (int i = 0; i < top.n; ++i) {
    if (is_split(i)) continue;
    rest.push_back(top.cand[size_t(i)]);
    where.push_back(i);
  }
  std::fill(top.prob.begin(), top.prob.begin() + top.n, 0.0);
  std::fill(top.gprob.begin(), top.gprob.begin() + top.n, 0.0);
  const int m = int(rest.size());
  if (m == 0) return false;
  prob.resize(size_t(m));
  b.rest_gprob.resize(size_t(m));
  choice_probabilities(rest, m, prob.data());
  top.guided = guide_choice(forest, prepared, rest, m, prob.data(), b.rest_gprob.data(), b.slots);
  for (int j = 0; j < m; ++j) {
    top.prob[size_t(where[size_t(j)])] = prob[size_t(j)];
    top.gprob[size_t(where[size_t(j)])] = b.rest_gprob[size_t(j)];
  }
  return true;
}

/// The guided choices of a traversal that chose top-level candidate i: that choice where it is a
/// guided one.
GuideTrail top_trail(const EdgeForest& forest, const PreparedQuery& prepared, const TopLevel& top, int i) {
  GuideTrail trail;
  if (top.guided) trail.add(candidate_slot(forest, prepared, top.cand[size_t(i)]), top.prob[size_t(i)]);
  return trail;
}

/// Whether this traversal follows the guided strategy: with probability 1 - s (ForestGuide::share)
/// where the query's cell has a guide (one random number), never (no number drawn) elsewhere.
bool guided_strategy(const PreparedQuery& prepared, const std::function<double()>& next) {
  return prepared.guide_values && next() >= prepared.q.guide->share();
}

/// From the top-level candidate `cur` (chosen with the probabilities `path` so far) down to an
/// edge and a point, by the guided strategy's choices (`guided`) or the unguided ones; the pdf is
/// the mixture of both (PathProbability).
SilhouetteSample descend(const EdgeForest& forest, const PreparedQuery& prepared, const std::function<double()>& next,
                         NodeTest test, Candidate cur, PathProbability path, bool guided, GuideTrail trail, int tests) {
  std::array<Candidate, 4> cand;
  std::array<double, 4> p4, g4;
  // ---- Descend: inner nodes choose among accepted children, leaves among silhouette edges,
  // small nodes among all the discontinuity edges below them.
  while (!cur.edge) {
    const ForestNode& node = forest.node(cur.node);
    if (is_flat(node, test, prepared.q.p)) {
      std::vector<Candidate>& flat = prepared.buffers.flat;
      std::vector<double>& prob = prepared.buffers.flat_prob;
      const int k = flat_candidates(forest, cur.node, prepared, flat, prob);
      const int i = k > 0 ? choose(prob.data(), k, next()) : -1;
      if (i < 0) {  // a false accept: no discontinuity below
        SilhouetteSample none;
        none.rejection_tests = tests;
        return none;
      }
      path.pu *= prob[size_t(i)];
      path.pg *= prob[size_t(i)];
      cur = flat[size_t(i)];
      break;
    }
    const int k = node.is_leaf() ? leaf_candidates(forest, cur.node, prepared, cand)
                                 : child_candidates(forest, cur.node, prepared, test, cand, tests);
    if (k == 0) {  // a false accept: no silhouette below (a zero-contribution traversal)
      SilhouetteSample none;
      none.rejection_tests = tests;
      return none;
    }
    level_probabilities(cand, k, p4);
    const bool guided_level =
        !node.is_leaf() && guide_choice(forest, prepared, cand, k, p4.data(), g4.data(), prepared.buffers.slots);
    if (node.is_leaf()) g4 = p4;
    const int i = choose(guided ? g4.data() : p4.data(), k, next());
    path.pu *= p4[size_t(i)];
    path.pg *= g4[size_t(i)];
    cur = cand[size_t(i)];
    if (guided_level) trail.add(candidate_slot(forest, prepared, cur), p4[size_t(i)]);
  }
  // ---- The point on the edge.
  SilhouetteSample out = sample_on_edge(*cur.edge, path.mixed(prepared), prepared, next(), tests);
  if (out.edge) {
    out.guide_slots = trail.slots;
    out.guide_pu = trail.pu;
    out.guide_levels = trail.levels;
  }
  return out;
}

}  // namespace

SilhouetteSample sample_silhouette(const EdgeForest& forest, const SilhouetteQuery& query,
                                   const std::function<double()>& next, NodeTest test) {
  EdgeChoiceScratch fallback;
  const PreparedQuery prepared = prepare(query, fallback);
  TopLevel& top = prepared.buffers.top_sample;
  top_level(forest, prepared, test, top);
  SilhouetteSample s;
  s.rejection_tests = top.tests;
  if (top.n == 0) return s;
  const bool guided = guided_strategy(prepared, next);
  const int i = choose(guided ? top.gprob.data() : top.prob.data(), top.n, next());
  if (i < 0) return s;
  return descend(forest, prepared, next, test, top.cand[size_t(i)], {top.prob[size_t(i)], top.gprob[size_t(i)]}, guided,
                 top_trail(forest, prepared, top, i), top.tests);
}

namespace {

/// The contour set's point (see sample_silhouette_set): an edge of `contour` chosen as a leaf
/// chooses among its edges, and t on it; no edge when the set is empty.
SilhouetteSample sample_contour(std::span<const Edge* const> contour, const PreparedQuery& prepared, double u_edge,
                                double u_t) {
  const int k = int(contour.size());
  if (k == 0) return {};
  std::vector<Candidate>& cand = prepared.buffers.contour_cand;
  std::vector<double>& prob = prepared.buffers.contour_prob;
  cand.clear();
  for (const Edge* e : contour) cand.push_back({-1, e, {}});
  prob.resize(size_t(k));
  if (k == 1) {
    prob[0] = 1.0;
  } else {
    for (Candidate& c : cand) c.w = leaf_edge_weight(*c.edge, prepared);
    choice_probabilities(cand, k, prob.data());
  }
  const int i = choose(prob.data(), k, u_edge);
  if (i < 0) return {};
  return sample_on_edge(*cand[size_t(i)].edge, prob[size_t(i)], prepared, u_t, 0);
}

}  // namespace

void sample_silhouette_set(const EdgeForest& forest, const SilhouetteQuery& query, const std::function<double()>& next,
                           NodeTest test, SilhouetteSampleSet& out) {
  out.count = 0;
  EdgeChoiceScratch fallback;
  const PreparedQuery prepared = prepare(query, fallback);
  TopLevel& top = prepared.buffers.top_set;
  top_level(forest, prepared, test, top);
  std::array<int, kMaxSplitEdges> idx;
  const int n_split = top.n > 0 ? split_indices(top, idx) : 0;
  // ---- The contour set, less the split edges (which keep their point of probability 1).
  std::vector<const Edge*>& contour = prepared.buffers.contour;
  contour.clear();
  for (const Edge* e : query.contour) {
    QSIL_DCHECK_MSG(is_discontinuity(*e, query.p), "a contour edge that is no discontinuity");
    bool split = false;
    for (int j = 0; j < n_split && !split; ++j) split = top.cand[size_t(idx[size_t(j)])].edge == e;
    if (!split) contour.push_back(e);
  }
  QSIL_DCHECK_MSG(std::set<const Edge*>(contour.begin(), contour.end()).size() == contour.size(),
                  "a contour edge listed twice");
  // Edges of the contour set are the contour strategy's: the traversal's points on them are dropped.
  auto push = [&](const SilhouetteSample& s) {
    if (s.edge && std::find(contour.begin(), contour.end(), s.edge) == contour.end()) out.push(s);
  };
  // ---- The contour set's point (its random numbers first: the traversal's stay as without it
  // when the set is empty).
  if (!contour.empty()) {
    const double u_edge = next(), u_t = next();
    const SilhouetteSample s = sample_contour(contour, prepared, u_edge, u_t);
    if (s.edge) out.push(s);
  }
  if (top.n == 0) return;
  for (int j = 0; j < n_split; ++j) {
    const SilhouetteSample s = sample_on_edge(*top.cand[size_t(idx[size_t(j)])].edge, 1.0, prepared, next(), 0);
    if (s.edge) out.push(s);
  }
  // The traversal chooses among the rest.
  if (n_split > 0 && !remove_split(forest, prepared, top, idx, n_split)) return;
  const bool guided = guided_strategy(prepared, next);
  const int i = choose(guided ? top.gprob.data() : top.prob.data(), top.n, next());
  if (i < 0) return;
  push(descend(forest, prepared, next, test, top.cand[size_t(i)], {top.prob[size_t(i)], top.gprob[size_t(i)]}, guided,
               top_trail(forest, prepared, top, i), top.tests));
}

std::vector<const Edge*> split_edges(const EdgeForest& forest, const SilhouetteQuery& query, NodeTest test,
                                           double* split_probability) {
  TopLevel top;
  EdgeChoiceScratch fallback;
  top_level(forest, prepare(query, fallback), test, top);
  std::array<int, kMaxSplitEdges> idx;
  const int n_split = top.n > 0 ? split_indices(top, idx) : 0;
  std::vector<const Edge*> out;
  double sum = 0;
  for (int j = 0; j < n_split; ++j) {
    out.push_back(top.cand[size_t(idx[size_t(j)])].edge);
    sum += top.prob[size_t(idx[size_t(j)])];
  }
  if (split_probability) *split_probability = sum;
  return out;
}

SilhouetteSample sample_on_edge(const Edge& e, double pmf, const SilhouetteQuery& query, double u,
                                int rejection_tests) {
  EdgeChoiceScratch fallback;
  return sample_on_edge(e, pmf, prepare(query, fallback), u, rejection_tests);
}

namespace {

SilhouetteSample sample_on_edge(const Edge& e, double pmf, const PreparedQuery& prepared, double u, int rejection_tests) {
  SilhouetteSample s;
  s.rejection_tests = rejection_tests;
  if (!is_discontinuity(e, prepared.q.p)) return s;
  const EdgePointSample ts = EdgeMixture(e, prepared.q, prepared.lights).sample(u);
  QSIL_DCHECK_MSG(pmf > 0 && ts.pdf > 0, "edge probability " << pmf << ", density of t " << ts.pdf);
  s.edge = &e;
  s.t = ts.t;
  s.pdf = pmf * ts.pdf;
  return s;
}

}  // namespace

namespace {

/// The probability with which a traversal from the top-level choice `top` reaches `edge`, by
/// walking the same choices (silhouette_edge_probability, traversal_edge_probability).
double walk_probability(const EdgeForest& forest, const PreparedQuery& prepared, NodeTest test, const TopLevel& top,
                        const Edge* edge) {
  // A candidate leads to `edge` when it is that edge or a node whose edge range holds it.
  auto leads_to = [&](const Candidate& c) {
    if (c.edge) return c.edge == edge;
    const std::span<const Edge> below = forest.node_edges(c.node);
    return edge >= below.data() && edge < below.data() + below.size();
  };
  int tests = top.tests;
  PathProbability path{0, 0};
  Candidate cur;
  for (int i = 0; i < top.n; ++i)
    if (leads_to(top.cand[size_t(i)])) {
      path = {top.prob[size_t(i)], top.gprob[size_t(i)]};
      cur = top.cand[size_t(i)];
    }
  if (path.pu == 0) return 0;
  std::array<Candidate, 4> cand;
  std::array<double, 4> p4, g4;
  while (!cur.edge) {
    const ForestNode& node = forest.node(cur.node);
    if (is_flat(node, test, prepared.q.p)) {
      std::vector<Candidate> flat;
      std::vector<double> prob;
      const int k = flat_candidates(forest, cur.node, prepared, flat, prob);
      for (int i = 0; i < k; ++i)
        if (flat[size_t(i)].edge == edge)
          return PathProbability{path.pu * prob[size_t(i)], path.pg * prob[size_t(i)]}.mixed(prepared);
      return 0;
    }
    const int k = node.is_leaf() ? leaf_candidates(forest, cur.node, prepared, cand)
                                 : child_candidates(forest, cur.node, prepared, test, cand, tests);
    if (k == 0) return 0;
    level_probabilities(cand, k, p4);
    if (node.is_leaf())
      g4 = p4;
    else
      guide_choice(forest, prepared, cand, k, p4.data(), g4.data(), prepared.buffers.slots);
    bool found = false;
    for (int i = 0; i < k && !found; ++i) {
      if (leads_to(cand[size_t(i)])) {
        path.pu *= p4[size_t(i)];
        path.pg *= g4[size_t(i)];
        cur = cand[size_t(i)];
        found = true;
      }
    }
    if (!found) return 0;
  }
  return path.mixed(prepared);
}

}  // namespace

namespace {

/// The probability of `edge` under the traversal of `query`, with the split edges taken out of the
/// top-level choice (`without_split`, as sample_silhouette_set does) or not.
double edge_probability(const EdgeForest& forest, const SilhouetteQuery& query, const Edge* edge, NodeTest test,
                        bool without_split) {
  EdgeChoiceScratch fallback;
  const PreparedQuery prepared = prepare(query, fallback);
  TopLevel top;
  top_level(forest, prepared, test, top);
  if (without_split) {
    std::array<int, kMaxSplitEdges> idx;
    const int n_split = top.n > 0 ? split_indices(top, idx) : 0;
    if (n_split > 0 && !remove_split(forest, prepared, top, idx, n_split)) return 0;
  }
  return walk_probability(forest, prepared, test, top, edge);
}

}  // namespace

double silhouette_edge_probability(const EdgeForest& forest, const SilhouetteQuery& query, const Edge* edge,
                                   NodeTest test) {
  return edge_probability(forest, query, edge, test, false);
}

double traversal_edge_probability(const EdgeForest& forest, const SilhouetteQuery& query, const Edge* edge,
                                  NodeTest test) {
  return edge_probability(forest, query, edge, test, true);
}

}  // namespace qsil::edgetree
