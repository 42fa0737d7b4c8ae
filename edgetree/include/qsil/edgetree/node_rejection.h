#pragma once
/// @file node_rejection.h
/// The rejection test of a forest node for a shading point [QSS 3.4, Appendix C; docs/architecture.md §5
/// "Rejection test"], the exact per-edge test of leaves and a brute-force reference.
///
/// Soundness is the invariant: may_have_silhouette() returns false only if no edge of the node's
/// patch is a silhouette for p, where "silhouette" is edge_is_silhouette() ((q0.x)(q1.x) <= 0
/// evaluated in double, world frame). Every tolerance leans toward accept; NaN or degenerate
/// computations accept.

#include "qsil/edgetree/edge_forest.h"
#include "qsil/math.h"

namespace qsil::edgetree {

/// Relative tolerance of the rejection test's sign decisions: a value within kRejectTol times
/// the magnitude of its terms (plus the rounding of the world coordinates, see
/// may_have_silhouette) counts as zero, i.e. as touching, i.e. accept.
inline constexpr double kRejectTol = 1e-9;

/// Which bound an inner forest node is tested with (the `--boundary` methods `quadric` and
/// `quadric-box` of the integrators' Method).
enum class NodeTest {
  DualBoxAndQuadrics,  ///< the dual box, then the bounding quadric pair [QSS 3.4]
  DualBox,             ///< the dual box only (the ablation of docs/architecture.md §7)
};

/// Rejection test of node `node` of `forest` for the shading point p (world frame), with the
/// bound `test` (NodeTest).
/// - Leaves: exact per-edge test (leaf_has_silhouette), for both tests.
/// - Unrejectable inner nodes: true.
/// - Inner nodes [QSS 3.4]: 1. the polygon C = B_q ∩ {r : [r,1].(A^T x') = 0} with x' the local
///   point [(p-c)/s, 1]; empty -> false. NodeTest::DualBox and box-only nodes: true otherwise.
///   2. a vertex with Q~0 <= 0 <= Q~1 -> true; 3. Q~0 or Q~1 has a root on a polygon edge
///   (sign change at the ends or interior extremum of the other sign) -> true; 4. a real point
///   of either conic (found on a line or its polar line, [QSS App. C]) inside C -> true;
///   5. false. Q~k(r) = [r,1]^T (A^T Qk A) [r,1].
bool may_have_silhouette(const EdgeForest& forest, int node, const Vec3& p, NodeTest test = NodeTest::DualBoxAndQuadrics);

/// The dual-space part of the test on a bound directly (steps 1-5 above; `box_only` stops after
/// step 1). Exposed for tests of degenerate patches fitted with fit_node().
bool bound_may_have_silhouette(const NodeBound& bound, bool box_only, const Vec3& p);

/// Exact test of a leaf: true iff one of its edges is a silhouette for p (edge_is_silhouette).
bool leaf_has_silhouette(const EdgeSet& edges, int leaf, const Vec3& p);

/// Brute force: true iff some edge of the node's subtree is a silhouette for p. O(edges).
bool node_has_silhouette(const EdgeSet& edges, int node, const Vec3& p);

}  // namespace qsil::edgetree
