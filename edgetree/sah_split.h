#pragma once
/// @file sah_split.h
/// Binned surface-area-heuristic split of a range of edges [QSS 4.1; Pharr et al. 2023, 4.3.2].

#include "qsil/edgetree/edge_set.h"

#include <span>

namespace qsil::edgetree {

/// An edge as the hierarchy build sees it: the box of its two endpoints (per axis the smaller and
/// the larger coordinate of p0 and p1; world frame, scene units) and the edge's index in the array
/// being ordered. The build sorts these 56-byte records, not the edges (Edge is about three times
/// larger), and then writes each edge once in its place (or, for edges already in their array,
/// moves them once). lo + hi equals p0 + p1 exactly (the same two
/// numbers added), so every centroid and every comparison is the one the edges would give.
struct EdgeBoxRef {
  Vec3 lo = Vec3::Zero();
  Vec3 hi = Vec3::Zero();
  int index = 0;
};

static_assert(sizeof(EdgeBoxRef) == 56, "EdgeBoxRef: the 56-byte record the build sorts");

/// sah_split scans ranges of at least this many edges in parallel (the top levels of a large
/// tree, which the level-parallel build does not divide).
inline constexpr int kParallelSplitEdges = 1 << 15;

/// The EdgeBoxRef of the edge from p0 to p1 with index `index`.
inline EdgeBoxRef edge_box_ref(const Vec3& p0, const Vec3& p1, int index) {
  return {p0.cwiseMin(p1), p0.cwiseMax(p1), index};
}

/// The EdgeBoxRef of edge `e` with index `index`.
inline EdgeBoxRef edge_box_ref(const Edge& e, int index) { return edge_box_ref(e.p0, e.p1, index); }

/// Partitions `edges` in place into two non-empty parts and returns the size of the first part
/// (0 < result < edges.size(); requires edges.size() >= 2). The split is the minimum over
/// `buckets` equal buckets of the largest axis of the box of edge centroids of
/// area(box of part A) * |A| + area(box of part B) * |B|, with boxes of the edges' endpoints.
/// If every centroid falls in one bucket (or the centroids coincide), splits at the median along
/// that axis (ties broken by the original order). Deterministic: a range of `parallel_from` edges
/// or more is scanned in parallel, in the same chunks whatever the threads do, and with finite
/// coordinates (minima, maxima and counts do not depend on order) with the serial scan's result;
/// the partition itself is serial.
int sah_split(std::span<EdgeBoxRef> edges, int buckets = 10, int parallel_from = kParallelSplitEdges);

}  // namespace qsil::edgetree
