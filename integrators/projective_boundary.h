#pragma once
/// @file projective_boundary.h
/// Projective sampling's secondary boundary term (Zhang, Roussel, Jakob 2023, "Projective Sampling
/// for Differentiable Rendering of Geometry", ACM TOG 42(6), §4-§5; the role of Mitsuba 3's
/// `prb_projective` with guiding "grid" or "none"; docs/architecture.md §16). Edge
/// samplers choose an edge per shading point; projective sampling draws *boundary segments*
/// instead, with no shading point: a point y on an edge and a direction w, uniformly over the
/// valid (y, w) of every edge, and finds the shading point p as the first hit from y along -w.
///
/// Estimator. The secondary boundary term of pixel j is, over the camera paths' vertices p
/// (docs/architecture.md §4-§5; boundary_term.h),
///   dI_j = sum over depths of integral We_j(path to p) f_s(p; w, wo) cos_s(w) dL(w) J dt dA_p,
/// with J dt = g . v_t dt, g = (w0 x w1) / |w_t|^3 (edge_sight), v_t the edge point's velocity
/// relative to p. With p = y - s w (s = |y - p|), dA_p = s^2 / |n_g(p) . w| dw, so per boundary
/// segment (t, w) drawn with density pdf(t, w):
///   contribution = W(p) F(p; w, wo) dL (g . v_t) s^2 / (|n_g(p) . w| pdf(t, w)),
/// F = f_s cos_s (bsdf_eval), W(p) the importance of p for the camera: a walk from p toward the
/// camera (light tracing: BSDF-sampled directions, each vertex q connected to the pinhole, whose
/// importance per unit area is We = f_x f_y / cos^3(theta) |n_g(q) . w_c| / r^2 in the pixel it
/// projects to, pixel units as primary_boundary.h; a step from q along u to q' weighs
/// F(q; wi, u) |n_g(q) . u| / (pdf(u) |n_g(q') . u|): the camera path's area measure at q' in terms
/// of the solid angle sampled at q, with F in the frame the camera path sees). As in Mitsuba 3, one connection among
/// the walk's visible ones is kept by reservoir sampling (its weight times their count), and the
/// jump dL is evaluated once, for that connection's path depth.
///
/// Velocities are relative to p (trap 2): p is moved as the camera path it ends reaches it, with
/// that path's directions fixed (the parametrization of the interior term, path_tracer.h): the
/// kept connection's vertices are retraced from the camera with duals. Every edge of every shape
/// is in the sample space, static ones too (seen from a moving p they move); see
/// make_projective_edges for the weights.
///
/// What it does not sample (measure zero in (t, w), though not in the per-vertex form): an edge in
/// p's own plane seen along that plane (OwnFace, edge_point.h), whose contribution comes from
/// smooth shading normals at grazing directions; docs/architecture.md §16 says where that matters.

#include "qsil/edgetree/edge_set.h"
#include "qsil/film.h"
#include "qsil/integrators/path_tracer.h"
#include "qsil/integrators/projective_sampling.h"
#include "qsil/parameters.h"

#include <cstdint>
#include <optional>
#include <vector>

namespace qsil {

/// Share of the boundary sample space's probability given to the edges of shapes that do not
/// move, when there are edges of both kinds: they contribute only where the shading point moves
/// (a moving shape, or a camera path through one), so they get less than their measure, never 0.
inline constexpr double kProjectiveStaticShare = 0.25;

/// Share of the walk's directions drawn uniformly on the sphere (the rest by BSDF sampling):
/// a defensive mixture, so that no direction the integrand reaches has zero density.
inline constexpr double kProjectiveUniformShare = 0.1;

/// A direction w of a boundary segment through an edge, drawn by sample_edge_direction: unit,
/// world; pdf its solid-angle density (1/sr).
struct EdgeDirection {
  Vec3 w = Vec3::Zero();
  double pdf = 0;
};

/// The measure (sr) of the directions along which edge e can be a discontinuity for a point on
/// the line through an edge point: the silhouette lune (n0 . w)(n1 . w) < 0 of an edge whose
/// faces' normals are n0 and n1, 4 x the angle between them, for a two-faced edge that is no
/// crease; the whole sphere (4 pi) for a crease, a boundary, non-manifold or inconsistent edge
/// and a segment of an intersection curve. 0 for a retired edge.
double edge_direction_measure(const edgetree::Edge& e);

/// A direction uniform over edge e's directions (edge_direction_measure) from three uniform
/// numbers: in the lune, the azimuth about the edge uniform in one of its two wedges (u.x chooses
/// and is reused) and cos of the angle to the edge uniform (u.y); on the sphere, uniform.
/// pdf = 1 / edge_direction_measure(e). A zero-measure edge gives pdf 0.
EdgeDirection sample_edge_direction(const edgetree::Edge& e, const Vec2& u);

/// The boundary sample space of projective sampling over an edge set: every edge (tree and
/// always-candidate edges, intersection-curve segments) with weight length x
/// edge_direction_measure (uniform over the valid (y, w)), the edges of shapes that do not move
/// scaled so that they hold kProjectiveStaticShare of the total when both kinds exist. The edges
/// point into the edge set.
struct ProjectiveEdges {
  std::vector<const edgetree::Edge*> edges;
  std::vector<double> cdf;  ///< cumulative weights (size edges + 1, cdf[0] = 0)
  bool empty() const { return edges.empty() || !(cdf.back() > 0); }
  /// The probability of edge i (its weight over the total).
  double probability(size_t i) const { return (cdf[i + 1] - cdf[i]) / cdf.back(); }
};

/// The sample space of `edges` (above); `moving[s]` tells whether shape (or crossing group) s
/// moves (an index it does not cover: moving).
ProjectiveEdges make_projective_edges(const edgetree::EdgeSet& edges, const std::vector<bool>& moving);

/// A boundary segment from a point u of the unit cube: u.x picks the edge by the cumulative
/// weights of `edges` and, as the remainder of its interval, t; (u.y, u.z) the direction
/// (sample_edge_direction). A measure-preserving map up to the densities: the segment's density
/// per unit t and steradian is edges.probability(edge) x direction pdf when u is uniform.
struct BoundarySegment {
  size_t edge = 0;  ///< index into ProjectiveEdges::edges
  double t = 0;     ///< edge parameter in [0, 1)
  EdgeDirection direction;
  double pdf = 0;  ///< per unit t and steradian, for u uniform; 0: no segment
};
BoundarySegment boundary_segment(const ProjectiveEdges& edges, const Vec3& u);

/// The inverse of boundary_segment: the point u of the unit cube that gives edge `edge` (an index
/// into edges.edges), parameter t in [0, 1) and unit direction w. None when w is not among the
/// edge's directions (outside its silhouette lune) or the edge has no measure.
std::optional<Vec3> invert_boundary_segment(const ProjectiveEdges& edges, size_t edge, double t, const Vec3& w);

/// Guiding of the boundary segments (Zhang, Roussel, Jakob 2023 §5): a piecewise-constant density
/// over cells of the unit cube of boundary_segment's u, mixed with the uniform density (a
/// defensive share), so that no segment the estimator can draw unguided has density 0.
/// Default-constructed: uniform. Two kinds of cells:
/// - a grid of resolution^3 equal cells, each weighted by the summed |contribution| of uniform
///   training segments that fell in it (the role of Mitsuba 3's guiding "grid");
/// - an octree, each leaf weighted by the mean |contribution| at the projected seeds that fell in
///   it times its volume (the role of Mitsuba 3's guiding "octree" with projection; octree()).
class SegmentGuide {
 public:
  SegmentGuide() = default;
  /// A grid from resolution^3 non-negative cell weights (x fastest, then y, then z) and the
  /// uniform share in (0, 1]; all-zero weights give the uniform density. QSIL_CHECKs the sizes.
  SegmentGuide(int resolution, const std::vector<double>& weights, double uniform_share);
  /// An octree over `points` (in the unit cube) with their non-negative `values`: a node is split
  /// into its eight octants while it holds more than `max_leaf` points and is shallower than
  /// `max_depth` (the root is depth 0; at most 20); each leaf's weight is the mean value of its points times
  /// its volume (0 for a leaf without points). The uniform share as for the grid. Deterministic:
  /// the same points in the same order give the same guide. QSIL_CHECKs matching sizes.
  static SegmentGuide octree(const std::vector<Vec3>& points, const std::vector<double>& values, int max_depth,
                             int max_leaf, double uniform_share);
  /// True when every u has density 1 by construction (no grid, no octree).
  bool uniform() const { return resolution_ == 0 && nodes_.empty(); }
  /// The grid's resolution (0 for the uniform guide and the octree).
  int resolution() const { return resolution_; }
  /// The number of cells (grid cells or octree leaves; 0 for the uniform guide).
  int cells() const { return int(cdf_.empty() ? 0 : cdf_.size() - 1); }
  /// The cell of u (index as for the weights, or the octree leaf); 0 for the uniform guide.
  int cell(const Vec3& u) const;
  /// Density of u relative to the uniform one: uniform_share + (1 - uniform_share) x the cell's
  /// weight / (the total weight x the cell's volume).
  double density(const Vec3& u) const;
  /// A point u from five uniform numbers: `choose` picks the uniform or the guided part, `pick`
  /// the cell by weight, `within` the position in the cell (or in the cube).
  Vec3 sample(double choose, double pick, const Vec3& within) const;

 private:
  /// An octree node: its first child (8 consecutive, octant x + 2 y + 4 z) or, for a leaf (-1),
  /// its cell.
  struct Node {
    int first = -1;
    int cell = -1;
  };
  int resolution_ = 0;
  double share_ = 1;
  std::vector<double> cdf_;   ///< cumulative cell weights (size cells + 1)
  std::vector<Node> nodes_;   ///< the octree (empty for a grid)
  std::vector<Vec3> lo_;      ///< octree: each leaf's lower corner
  std::vector<double> size_;  ///< octree: each leaf's side
};

/// Trains a grid SegmentGuide over `edges` (the file comment's estimator, its |value| summed over
/// the parameters and channels per cell): guiding.training x W x H uniform segments in chunks,
/// each from its stream (stream::kProjectiveTraining), merged in chunk order (the same guide for
/// any thread count). The uniform guide for resolution 0 or an empty sample space. Counts rays
/// in `stats`.
SegmentGuide train_segment_guide(const PathContext& ctx, const SceneVelocities& velocities,
                                 const ProjectiveEdges& edges, const ProjectiveGuiding& guiding, int threads,
                                 PathStats& stats);

/// Octree limits of the projected guide (train_projected_guide): a leaf holds at most
/// kOctreeMaxLeaf seeds unless it is at depth kOctreeMaxDepth (65 536 cells per axis: finer than
/// the edges of u.x on a 10^4-edge scene). Each seed's value is one sample of the estimator, so
/// a leaf's mean over few seeds is noisy: 16 per leaf guided worse than 64 and 256 on
/// shadow-quad and sphere-light (docs/experiments/2026-11-26-projective-sampling.md §4).
inline constexpr int kOctreeMaxDepth = 16;
inline constexpr int kOctreeMaxLeaf = 64;

/// Most camera paths train_projected_guide draws (2^24: about 10^7 seeds of 32 bytes at most).
inline constexpr long long kMaxSeedPaths = 1LL << 24;

/// Trains an octree SegmentGuide over `edges` from projected seeds (Zhang, Roussel, Jakob 2023
/// §5.2; silhouette_projection.h): guiding.seeds x W x H camera paths rounded up to a whole chunk
/// of 1024 (a random pixel each), each
/// vertex with a segment left giving two seeds, the hit of a light sample's ray (an occluder
/// between the vertex and the light) and the hit of the BSDF-sampled ray the path continues
/// with; each seed projected onto a boundary segment (project_seed) and the estimator's |value|
/// there (as train_segment_guide's) recorded; then SegmentGuide::octree over them
/// (kOctreeMaxDepth, kOctreeMaxLeaf). Paths in chunks, each from its stream
/// (stream::kProjectiveSeeds), merged in chunk order (the same guide for any thread count). The uniform guide
/// when guiding.octree is false, the sample space is empty or no seed projects. Throws
/// qsil::Error when the paths would be more than kMaxSeedPaths. Counts rays in `stats`; `seeds`
/// (optional) receives the number of projected seeds.
SegmentGuide train_projected_guide(const PathContext& ctx, const SceneVelocities& velocities,
                                   const ProjectiveEdges& edges, const ProjectiveGuiding& guiding, int threads,
                                   PathStats& stats, long long* seeds = nullptr);

/// Boundary segments per sample index for a W x H image at `ratio` segments per pixel sample:
/// ratio W H rounded up to a whole chunk of 1024 (at least one). Throws qsil::Error unless ratio
/// is in (0, 1024].
long long projective_samples_per_index(int width, int height, double ratio);

/// Adds the secondary boundary term of the sample range [first_sample, first_sample + spp) to the
/// derivative channels of `film` (a gradient film of velocities.num_params parameters) by
/// projective sampling (the file comment): projective_samples_per_index(W, H, ratio) boundary
/// segments per sample index, their u drawn from `guide` (its density divides their weight), numbered and drawn in
/// chunks as the primary term's (sample_chunks.h), chunk c from its stream (stream::kProjectiveSegments), splatted
/// where their connection lands. Deterministic for a seed whatever the thread count. Counts rays, boundary segments (as
/// traversals) and zero contributions in `stats`; returns the number of contributions that were not finite (replaced by
/// zero). Part `part` of `parts` and `deferred` as for add_primary_boundary.
uint64_t add_projective_boundary(Film& film, const PathContext& ctx, const SceneVelocities& velocities,
                                 const ProjectiveEdges& edges, const SegmentGuide& guide, double ratio,
                                 int first_sample, int spp, uint64_t seed, int threads, PathStats& stats, int part = 0,
                                 int parts = 1, std::vector<FilmSplat>* deferred = nullptr);

}  // namespace qsil
