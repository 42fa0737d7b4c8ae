#pragma once
/// @file sah_split.h
/// Binned surface-area-heuristic split of a range of edges [QSS 4.1; Pharr et al. 2023, 4.3.2].

#include "qsil/edgetree/edge_set.h"

#include <span>

namespace qsil::edgetree {

/// Partitions `edges` in place into two non-empty parts and returns the size of the first part
/// (0 < result < edges.size(); requires edges.size() >= 2). The split is the minimum over
/// `buckets` equal buckets of the largest axis of the box of edge centroids of
/// area(box of part A) * |A| + area(box of part B) * |B|, with boxes of the edges' endpoints.
/// If every centroid falls in one bucket (or the centroids coincide), splits at the median along
/// that axis (ties broken by the original order). Deterministic.
int sah_split(std::span<Edge> edges, int buckets = 10);

}  // namespace qsil::edgetree
