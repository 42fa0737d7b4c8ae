#pragma once
/// @file silhouette_sampler.h
/// Stochastic top-down traversal of the edge forest for one shading point [QSS 3.4-3.6, 4.1;
/// docs/architecture.md §5 "Importance", "Point on the edge"]: sample one discontinuity edge and a
/// point on it, with the exact probability of having done so.
///
/// At every level (the forest roots included) children that the rejection test rejects get
/// probability 0; the others are chosen with probability
///   P(i) = (1 - eps) I_i / sum I + eps * G_i / sum G,  I_i = L_w / H^2 * fbar,  G_i = L_w / H^2,
/// H the distance from p to the centre of B_p (at least half its diagonal), fbar the mean
/// cosine-weighted BSDF over B_p's solid angle times the radiance (environment, every light;
/// NodeWeight). The defensive share keeps P(i) > 0 where fbar = 0 but the integrand need not be.
/// A leaf chooses among its silhouette edges the same way (leaf_edge_weight); t comes from
/// EdgeMixture. Always-candidate edges compete with the forest roots at the top level, through
/// their always-candidate tree (never rejected) or, when few, one by one (loose_edge_weight).
/// Beyond the paper (NodeTest::DualBoxAndQuadrics only; each keeps every probability > 0):
/// - flat choice: a chosen node of <= 64 edges, or of <= 1024 whose box's bounding sphere holds p,
///   chooses among all its edges at once by their leaf weights (a box spreads a narrow lobe's or a
///   light's weight over every box it overlaps, and cannot follow 1/distance² near p);
/// - splitting and contour sets (sample_silhouette_set): fixed per query, each edge estimated by
///   exactly one strategy. Measured: docs/experiments/2026-11-25-edge-choice.md, -header-notes.md;
/// - guiding (SilhouetteQuery::guide, forest_guide.h; off unless a guide is given): the choices at
///   the upper levels follow, with probability 1 - s, a learnt correction of those above, and the
///   pdf is the mixture of both strategies over the whole path (>= s x the unguided one).

#include "qsil/edgetree/contour_set.h"
#include "qsil/edgetree/edge_choice_scratch.h"
#include "qsil/edgetree/edge_forest.h"
#include "qsil/edgetree/forest_guide.h"
#include "qsil/edgetree/ltc.h"
#include "qsil/edgetree/node_rejection.h"
#include "qsil/math.h"
#include "qsil/parameters.h"

#include <array>
#include <functional>
#include <span>
#include <vector>

namespace qsil::edgetree {

/// A polygonal (quad) area light for the light-aware importance I_light [QSS 3.6].
struct LightPolygon {
  std::array<Vec3, 4> corners;  ///< world positions, in order around the quad
  Vec3 normal = Vec3::Zero();   ///< emitting side (unit, world)
  double weight = 0;            ///< its radiance (luminance)
  int shape = -1;               ///< its shape in the scene (-1: none); a light probe's ray that hits it is a miss
};

/// A light that is not a quad (a mesh emitter: a sphere light, an emissive OBJ), known to the
/// light-aware importance by a sphere that bounds its vertices. Seen from a point p outside the
/// sphere it becomes a quad facing p that covers the sphere's whole cone (light_billboard), so
/// every node and edge importance that handles quad lights handles it, and never gives a
/// direction toward the emitter less radiance than the emitter's; from inside, it adds its
/// radiance to the query's environment weight (enclosing_light_weight).
struct LightSphere {
  Vec3 centre = Vec3::Zero();  ///< world
  double radius = 0;           ///< world units; every vertex of the emitter lies within it
  double weight = 0;           ///< its radiance (luminance), as LightPolygon::weight
  int shape = -1;              ///< its shape in the scene, as LightPolygon::shape
};

/// Everything the traversal needs to know about the shading point.
struct SilhouetteQuery {
  Vec3 p = Vec3::Zero();  ///< shading point (world)
  Frame frame;            ///< local shading frame (z = shading normal), world -> local
  LTC ltc;                ///< the BSDF's LTC in that frame (norm = albedo weight)
  /// eligible[s]: edges of shape s may contribute (their velocity relative to p is non-zero).
  /// Null: every shape is eligible. An index beyond its size (a crossing group the vector does
  /// not cover, CrossingGroup) is eligible: eligibility only saves work, so an unknown one is
  /// kept (a zero relative velocity gives a zero contribution, never a bias).
  const std::vector<bool>* eligible = nullptr;
  /// Light-aware importance [QSS 3.6]: fbar = env_weight * fbar(Omega(B_p)) + sum over lights of
  /// weight * (integral of f_s cos over Omega(B_p) ∩ Omega(light)) / |Omega(B_p)|, summed over
  /// ALL lights (the paper supports one). Without lights: env_weight * fbar (env_weight 1 by
  /// default, so plain [QSS 3.5] importance).
  const std::vector<LightPolygon>* lights = nullptr;
  /// Lights that are not quads (LightSphere): each a quad facing p (light_billboard) beside
  /// `lights` wherever p lies outside its sphere. Null: none.
  const std::vector<LightSphere>* light_spheres = nullptr;
  double env_weight = 1.0;
  /// Per shape: the luminance of its emitted radiance (0 for a shape that does not emit), or
  /// null. The outline of an emitter bounds a jump of that radiance: its edges weigh it.
  const std::vector<double>* emission = nullptr;
  /// Velocities for the leaves' normal-velocity factor (velocity_factor), or null (factor 1).
  const SceneVelocities* velocities = nullptr;
  SceneVelocities::Block dp = SceneVelocities::Block::Zero();  ///< dp/dtheta of p (world, 3 x kMaxParameters)
  /// Per parameter: 1 / the largest |dx/dtheta_k| over the scene's vertices (0: unused), so that
  /// parameters of different units weigh alike in velocity_factor.
  std::array<double, kMaxParameters> velocity_scale{};
  /// The contour set of the query (contour_set.h; made by the boundary term, boundary_contour_set,
  /// once per shading point): distinct discontinuity edges of eligible shapes that
  /// sample_silhouette_set estimates by a strategy of their own. Empty (the default): none.
  /// The edges must outlive the query's use.
  std::span<const Edge* const> contour;
  /// Scratch memory of this thread for the edge choice (edge_choice_scratch.h); null: each call
  /// makes its own.
  EdgeChoiceScratch* scratch = nullptr;
  /// A learnt distribution over the forest's upper levels (forest_guide.h) mixed into the choices
  /// among its slots, or null (unguided). Made for the forest the traversal walks.
  const ForestGuide* guide = nullptr;

  /// True when edges of shape (or crossing group) `shape` may contribute (see `eligible`).
  bool is_eligible(int shape) const {
    return !eligible || shape >= int(eligible->size()) || (*eligible)[size_t(shape)];
  }
};

/// The corners of `light` relative to the query point in its local shading frame (`local`), when
/// the light emits toward that point (positive weight, emitting side facing it); false otherwise
/// (`local` untouched). The light-aware importance's per-light set-up [QSS 3.6].
inline bool light_toward(const LightPolygon& light, const SilhouetteQuery& q, std::array<Vec3, 4>& local) {
  if (!(light.weight > 0) || light.normal.dot(q.p - light.corners[0]) <= 0) return false;
  for (int i = 0; i < 4; ++i) local[size_t(i)] = q.frame.to_local(light.corners[size_t(i)] - q.p);
  return true;
}

/// The quad that stands for `light` seen from `p` (LightSphere): in the plane through the
/// sphere's centre c perpendicular to the direction a = (c - p) / D, D = |c - p|, a square
/// centred at c with half-side D tan(beta), sin(beta) = radius / D, which holds the circle where
/// the cone from p tangent to the sphere meets that plane; so every ray from p that meets the
/// sphere passes through the square. Normal -a (the emitting side faces p), the light's weight
/// and shape. False (`out` untouched) where p lies inside the sphere or on it (D <= radius: no
/// quad holds the cone) or the light has no weight.
bool light_billboard(const LightSphere& light, const Vec3& p, LightPolygon& out);

/// Calls f(light) for every light of query q as a quad: those of q.lights, then, for each of
/// q.light_spheres with p outside its sphere, the quad that stands for it (light_billboard).
template <class F>
void for_each_light_quad(const SilhouetteQuery& q, F&& f) {
  if (q.lights)
    for (const LightPolygon& light : *q.lights) f(light);
  if (q.light_spheres) {
    LightPolygon quad;
    for (const LightSphere& sphere : *q.light_spheres)
      if (light_billboard(sphere, q.p, quad)) f(quad);
  }
}

/// The radiance (luminance) of the lights of `spheres` whose sphere holds `p` (D <= radius, where
/// light_billboard gives no quad): seen from inside, a light may lie in any direction, so the
/// light-aware importance counts it as part of the environment. 0 for none.
double enclosing_light_weight(const std::vector<LightSphere>* spheres, const Vec3& p);

/// A light as seen from one query point: the corners of its quad relative to p in the local
/// shading frame, and the normals of the four sides of the pyramid from p over it, oriented so
/// that n · w >= 0 for directions w inside. The per-query constants of the light-aware importance
/// [QSS 3.6], computed once per traversal (local_lights) instead of at every node.
struct LocalLight {
  std::array<Vec3, 4> corners;      ///< local frame, relative to p (scene units)
  std::array<Vec3, 4> sides;        ///< inward unit side normals (local frame; zero for a degenerate side)
  std::array<Vec3, 4> sides_world;  ///< the same normals in the world frame
  double weight = 0;                ///< the light's radiance (luminance)
};

/// The lights of `q` that emit toward q.p (light_toward), in order, as LocalLight: the quads of
/// q.lights, then the quads of q.light_spheres facing q.p (light_billboard); `out` is cleared
/// first. Empty when both are null.
void local_lights(const SilhouetteQuery& q, std::vector<LocalLight>& out);

/// A sampled edge point and its probability.
struct SilhouetteSample {
  const Edge* edge = nullptr;  ///< nullptr: no edge (every candidate was rejected)
  double t = 0;                      ///< point x0 + t (x1 - x0) on the edge
  double pdf = 0;                    ///< discrete probability of the edge times the density of t
  int rejection_tests = 0;           ///< number of node tests performed
  /// With a guide (SilhouetteQuery::guide): the guided choices of the traversal that made this
  /// sample, the keys of its training records (ForestGuide::train): at each of `guide_levels`
  /// levels among two or more guided slots, the slot chosen and its unguided probability there.
  /// None for a split edge's and the contour set's points (chosen by no traversal).
  std::array<int, kMaxGuideLevels> guide_slots{};
  std::array<double, kMaxGuideLevels> guide_pu{};
  int guide_levels = 0;
};

/// Loose always-candidate edges at or above this top-level probability are split
/// (sample_silhouette_set); a split edge costs about a tenth of a traversal at every traversal.
/// Value measured on shadow-quad: docs/experiments/2026-11-25-edge-choice.md §5 "Splitting".
inline constexpr double kSplitShare = 1.0 / 32.0;
/// At most this many edges are split per traversal (the most probable ones).
inline constexpr int kMaxSplitEdges = 8;

/// The edge points of one traversal with splitting: up to kMaxSplitEdges split edges (each with
/// pdf = its density of t), the traversal's own sample (possibly none) and the contour set's
/// (possibly none). The boundary term at the query point is estimated by the sum over all of
/// them of integrand / pdf.
struct SilhouetteSampleSet {
  std::array<SilhouetteSample, kMaxSplitEdges + 2> samples{};
  int count = 0;
  void push(const SilhouetteSample& s) { samples[size_t(count++)] = s; }
};

/// Samples with splitting: a loose always-candidate edge whose top-level probability (that of
/// sample_silhouette) is at least kSplitShare (at most kMaxSplitEdges, the most probable) gets a
/// point of its own (discrete probability 1), and the traversal chooses among the other
/// candidates afresh (their weights normalised over them alone, eps as at every choice; not the
/// old probabilities rescaled, which left the rest's choice mostly defensive). The split set
/// depends on p alone. Output in `out` (cleared first): the split edges' points, then the
/// traversal's (omitted when it finds no edge); `next` as for sample_silhouette.
///
/// With a contour set (query.contour; contour_set.h) the boundary term splits into the sum over
/// the set's edges that are not split and the sum over every other edge: the traversal and the
/// split edges estimate the second, the traversal's points on edges of the set are dropped (a
/// zero contribution: those edges are the other strategy's), and one more point estimates the
/// first, on an edge of the set (split edges left out) chosen with probability
///   P(e) = (1 - eps) I_e / sum I + eps G_e / sum G   (I, G: leaf_edge_weight; eps as a leaf's),
/// its t from EdgeMixture, drawn first (two random numbers). Each edge is covered by exactly
/// one strategy with positive probability, so the sum stays unbiased whatever the set.
void sample_silhouette_set(const EdgeForest& forest, const SilhouetteQuery& query, const std::function<double()>& next,
                           NodeTest test, SilhouetteSampleSet& out);

/// The edges sample_silhouette_set splits for the query and the sum of their top-level
/// probabilities (those of sample_silhouette). For tests and `qsil candidates`.
std::vector<const Edge*> split_edges(const EdgeForest& forest, const SilhouetteQuery& query, NodeTest test,
                                           double* split_probability = nullptr);

/// Samples one discontinuity edge and a point on it for the query (no splitting), with the rejection test of
/// `test` (NodeTest, node_rejection.h). `next` returns a fresh
/// uniform number in [0,1) each call.
SilhouetteSample sample_silhouette(const EdgeForest& forest, const SilhouetteQuery& query,
                                   const std::function<double()>& next, NodeTest test = NodeTest::DualBoxAndQuadrics);

/// Completes a sample on a chosen edge e (chosen with discrete probability pmf): t from the
/// light-aware EdgeMixture of the query ([QSS Eq. 4] x LTC, weighted by the radiance that can
/// jump at each part of the edge, defensive in angle) with u, pdf = pmf x
/// pdf(t). Returns no edge when e is not a discontinuity for the query point (is_discontinuity):
/// samplers without an exact leaf test (vsphere, uniform) land there, a zero-contribution sample.
/// `rejection_tests` (the tests the choice of e took) is stored in the result.
SilhouetteSample sample_on_edge(const Edge& e, double pmf, const SilhouetteQuery& query, double u,
                                int rejection_tests = 0);

/// Boxes seen under a bounding cone of sin(half-angle) = half diagonal / distance below this are
/// weighed by the cone (NodeWeight), and under the cosine lobe edges whose half length / distance
/// is below it by EdgeMixture::far_total (leaf_edge_weight): time for accuracy. Value measured in
/// docs/experiments/2026-11-25-edge-choice.md §5 "Importance".
inline constexpr double kConeImportanceSin = 0.5;

/// Factor on both weights (importance and defensive) of a smooth crease (Edge::smooth_crease)
/// that is no silhouette for p, under the cosine lobe, at a leaf or flat choice and as a loose
/// always-candidate; and on a node's L_w, the part of its concave smooth creases
/// (ForestNode::lw_smooth, silhouettes or not: a node cannot tell). Such a crease's radiance jumps
/// only in the slivers where a face's shading and geometric normals disagree, which few paths
/// find. Below 1 keeps the choice unbiased (every probability stays positive); glossy lobes keep
/// full weight (seen through a narrow lobe the sliver jumps carry more). Measured:
/// docs/design-notes.md "Crease samples".
inline constexpr double kSmoothCreaseWeight = 0.1;

/// Importance I and defensive weight G of a node for the query (see the file comment). fbar is
/// the mean of f_s cos times the radiance over the box's solid angle: exact (LTC integrals over
/// the box's outline, clipped by each light's pyramid) for near boxes; for a box far from p (half
/// diagonal < kConeImportanceSin × distance of its centre) taken over its bounding cone instead
/// (cosine lobe: n . w uniform on its range over the cone; glossy lobe: the form factor of the
/// cone's image under M⁻¹, [LTC] Eq. 11, as a spherical ellipse, or the exact form where that
/// image may reach 90° from its centre; docs/experiments/2026-11-25-edge-choice.md §5
/// "Importance"). Zero only where the exact fbar is zero, up to the ellipse approximation (the
/// defensive share covers any); within 3 % of it for boxes under sin α ≤ 0.05 wholly above the
/// horizon and wholly in or out of each light (tests/edgetree/node_importance_test.cpp). Both
/// weights use L_w with its lw_smooth part times kSmoothCreaseWeight under the cosine lobe.
struct NodeWeight {
  double importance = 0;
  double defensive = 0;
};
NodeWeight node_weight(const ForestNode& node, const SilhouetteQuery& query);

/// Importance of an edge in a leaf or a flat choice (docs/architecture.md §5 "Importance"): the
/// radiance-weighted LTC integral of EdgeMixture (the [QSS Eq. 4] term with f_s cos, weighted by
/// the environment, by each light over the part of the edge in front of it, and for an emitter's
/// outline by its own radiance) times velocity_factor; defensive weight: length / distance² of its
/// midpoint. Under the cosine lobe an edge far from p (half length < kConeImportanceSin × the
/// distance of its midpoint) takes EdgeMixture::far_total instead (the same components with the
/// edge's distance taken as its midpoint's: no LTC set-up, no angles), within 3 % of the
/// integral for edges shorter than 0.1 × their distance wholly above the horizon and wholly in
/// or out of each light (tests/edgetree/edge_importance_test.cpp). Both weights times
/// kSmoothCreaseWeight where it applies.
NodeWeight leaf_edge_weight(const Edge& e, const SilhouetteQuery& q);

/// Importance of a loose always-candidate edge, which competes with the forest roots: on the
/// roots' scale (a node's I is about π times the radiance-weighted integral over its silhouettes),
/// π × the radiance-weighted LTC integral; defensive weight π × length / distance²; both times
/// kSmoothCreaseWeight where it applies.
NodeWeight loose_edge_weight(const Edge& e, const SilhouetteQuery& q);

/// The normal-velocity factor of an edge for the query (1 without velocities): the mean over its
/// endpoints of sum_k |n . (v_k - dp_k)| velocity_scale[k], n the unit normal of the plane through
/// p and the edge. J of [QSS Eq. 3] is proportional to n . (v(t) - dp), which is linear in t, so
/// this bounds its mean over the edge: 0 only where every point of the edge moves within that
/// plane (e.g. an edge of p's own triangle under a rigid motion), where the integrand is 0 too.
double velocity_factor(const Edge& e, const SilhouetteQuery& q);

/// Probability with which sample_silhouette (with `test`) picks `edge` (an element of
/// forest.edges() or forest.always_edges()) for the query, by walking the same choices (for
/// tests: the sampling probabilities of all edges sum to at most 1, and match the histogram).
double silhouette_edge_probability(const EdgeForest& forest, const SilhouetteQuery& query, const Edge* edge,
                                   NodeTest test = NodeTest::DualBoxAndQuadrics);

/// Probability with which the traversal of sample_silhouette_set (after splitting, without a
/// contour set) picks `edge`: 0 for a split edge, otherwise the walk of
/// silhouette_edge_probability from the top-level choice among the non-split candidates. For
/// tests (the histogram of split_sampling_test).
double traversal_edge_probability(const EdgeForest& forest, const SilhouetteQuery& query, const Edge* edge,
                                  NodeTest test = NodeTest::DualBoxAndQuadrics);

}  // namespace qsil::edgetree
