/// @file edge_set.cpp
/// Edge extraction per shape and the top-down 4-wide SAH hierarchy [QSS 4.1]; see
/// qsil/edgetree/edge_set.h.

#include "qsil/edgetree/edge_set.h"

#include "sah_split.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <deque>
#include <tuple>

namespace qsil::edgetree {

namespace {

// Splits [b, e) into 2..4 groups: one binary SAH split, then each half again if it is larger
// than a leaf [QSS 4.1: three binary splits per level].
std::vector<std::pair<int, int>> split4(std::vector<Edge>& edges, int b, int e, const EdgeSetOptions& opt) {
  std::vector<std::pair<int, int>> out;
  const int m = b + sah_split(std::span(edges.data() + b, size_t(e - b)), opt.sah_buckets);
  for (auto [lo, hi] : {std::pair{b, m}, std::pair{m, e}}) {
    if (hi - lo > opt.leaf_size) {
      const int mm = lo + sah_split(std::span(edges.data() + lo, size_t(hi - lo)), opt.sah_buckets);
      out.push_back({lo, mm});
      out.push_back({mm, hi});
    } else {
      out.push_back({lo, hi});
    }
  }
  return out;
}

/// Top-down 4-wide topology over edges [ebase, eend) of `edges` (reordered in place), appended
/// to `nodes` breadth-first so that every level is a contiguous node range; the root is
/// discarded, its children become `roots`. Nodes of an always-candidate tree carry kNodeAlways.
/// Returns the node range of every level; `depth` receives the number of levels.
std::vector<std::pair<int, int>> build_topology(std::vector<Edge>& edges, int ebase, int eend, int shape,
                                                bool always, const EdgeSetOptions& opt, std::vector<ForestNode>& nodes,
                                                std::vector<int>& roots, int& depth) {
  std::vector<std::pair<int, int>> levels;
  depth = 0;
  if (eend <= ebase) return levels;
  const int nbase = int(nodes.size());
  std::vector<std::pair<int, int>> top;
  if (eend - ebase <= opt.leaf_size)
    top.push_back({ebase, eend});
  else
    top = split4(edges, ebase, eend, opt);
  auto add_node = [&](int b, int e, int parent, int d) {
    ForestNode n;
    n.edge_begin = b;
    n.edge_end = e;
    n.parent = parent;
    n.shape = shape;
    n.depth = std::uint16_t(d);
    if (always) n.flags |= kNodeAlways;
    if (e - b <= opt.leaf_size) {
      n.flags |= kNodeLeaf;
      n.first = b;
      n.count = e - b;
    }
    nodes.push_back(n);
  };
  for (auto [b, e] : top) {
    roots.push_back(int(nodes.size()));
    add_node(b, e, -1, 0);
  }
  int level_begin = nbase;
  while (level_begin < int(nodes.size())) {
    const int level_end = int(nodes.size());
    levels.push_back({level_begin, level_end});
    for (int i = level_begin; i < level_end; ++i) {
      if (nodes[i].is_leaf()) continue;
      const auto groups = split4(edges, nodes[i].edge_begin, nodes[i].edge_end, opt);
      nodes[i].first = int(nodes.size());
      nodes[i].count = int(groups.size());
      for (auto [b, e] : groups) add_node(b, e, i, depth + 1);
    }
    level_begin = level_end;
    ++depth;
  }
  // ---- B_p and L_w of every node (edges are in their final order now), in parallel
  tbb::parallel_for(nbase, int(nodes.size()), [&](int i) {
    ForestNode& n = nodes[i];
    for (int k = n.edge_begin; k < n.edge_end; ++k) {
      n.bp.expand(edges[k].p0);
      n.bp.expand(edges[k].p1);
      n.lw += always ? always_edge_weight(edges[k]) : edges[k].length * edges[k].angle;
      if (edges[k].smooth_crease && edges[k].cls == EdgeClass::Concave) n.lw_smooth += always_edge_weight(edges[k]);
    }
  });
  return levels;
}

/// Edge idx of `set` as a forest edge, with its end points (world frame) from `mesh`.
Edge forest_edge(const MeshEdgeSet& set, const TriangleMesh& mesh, int idx) {
  Edge fe;
  static_cast<MeshEdge&>(fe) = set.edges[idx];
  fe.p0 = mesh.positions[fe.v0];
  fe.p1 = mesh.positions[fe.v1];
  return fe;
}

/// A shape's always-candidate edges: set.always (boundary, non-manifold, inconsistent), then the
/// creases of `in` (all of them for a flat-shaded shape), marked in is_crease (one entry per edge
/// of `set`) and counted in st.creases.
std::vector<Edge> shape_always_edges(const ForestShapeInput& in, const MeshEdgeSet& set,
                                           std::vector<char>& is_crease, ForestShapeStats& st) {
  const TriangleMesh& mesh = *in.mesh;
  const CreaseSet creases = in.face_normals ? CreaseSet::All : in.creases;
  std::vector<Edge> always;
  for (int idx : set.always) always.push_back(forest_edge(set, mesh, idx));
  for (size_t idx = 0; idx < set.edges.size(); ++idx) {
    const EdgeClass cls = set.edges[idx].cls;
    if ((cls == EdgeClass::Concave && creases != CreaseSet::None) ||
        (cls == EdgeClass::Convex && creases == CreaseSet::All)) {
      is_crease[idx] = 1;
      always.push_back(forest_edge(set, mesh, int(idx)));
      always.back().crease = true;
      always.back().smooth_crease = !in.face_normals;
      ++st.creases;
    }
  }
  return always;
}

/// Counts nodes[nbase, end) into st.nodes, st.leaves and st.inner_nodes.
void count_nodes(const std::vector<ForestNode>& nodes, int nbase, ForestShapeStats& st) {
  for (int i = nbase; i < int(nodes.size()); ++i) {
    st.nodes++;
    if (nodes[size_t(i)].is_leaf())
      st.leaves++;
    else
      st.inner_nodes++;
  }
}

}  // namespace

EdgeSet EdgeSet::build(std::span<const ForestShapeInput> shapes, const EdgeSetOptions& options) {
  EdgeSet f;
  EdgeSetOptions opt = options;
  opt.leaf_size = std::clamp(opt.leaf_size, 1, 4);
  for (const ForestShapeInput& in : shapes) {
    const auto t0 = std::chrono::steady_clock::now();
    ForestShapeStats st;
    st.shape = in.shape;
    const TriangleMesh& mesh = *in.mesh;

    // ---- edges
    MeshEdgeSet set = build_mesh_edges(mesh, in.shape, opt.edges);
    st.edge_counts = set.counts;
    st.edges_total = int(set.edges.size());
    st.edges_kept = int(set.kept.size());
    st.edges_always = int(set.always.size());
    // ---- always-candidate edges: boundary, non-manifold, inconsistent, and the creases
    std::vector<char> is_crease(set.edges.size(), 0);
    const std::vector<Edge> always = shape_always_edges(in, set, is_crease, st);
    st.edges_always = int(always.size());
    const int abase = int(f.always_.size());
    f.always_.insert(f.always_.end(), always.begin(), always.end());
    const int aend = int(f.always_.size());
    if (aend - abase > opt.always_tree_min_edges) {
      const int n0 = int(f.nodes_.size());
      int always_depth = 0;
      build_topology(f.always_, abase, aend, in.shape, /*always=*/true, opt, f.nodes_, f.always_roots_, always_depth);
      st.always_nodes = int(f.nodes_.size()) - n0;
    } else {
      for (int i = abase; i < aend; ++i) f.loose_always_edges_.push_back(i);
    }

    // ---- silhouette tree edges: the kept edges that are not creases (a flat-shaded shape has
    // none: its crease branch covers silhouettes too)
    const int ebase = int(f.edges_.size());
    if (!in.face_normals)
      for (int idx : set.kept)
        if (!is_crease[size_t(idx)]) f.edges_.push_back(forest_edge(set, mesh, idx));
    const int eend = int(f.edges_.size());
    st.edges_kept = eend - ebase;

    // ---- topology and B_p, L_w of every node
    const int nbase = int(f.nodes_.size());
    int depth = 0;
    const size_t roots_before = f.roots_.size();
    ShapeTree tree;
    tree.levels = build_topology(f.edges_, ebase, eend, in.shape, /*always=*/false, opt, f.nodes_, f.roots_, depth);
    tree.face_planes = std::move(set.face_planes);
    f.trees_.push_back(std::move(tree));
    st.roots = int(f.roots_.size() - roots_before);
    st.depth = depth;
    count_nodes(f.nodes_, nbase, st);
    st.build_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    f.stats_.push_back(st);
  }
  if (opt.intersection_curves) add_crossings(f, shapes, opt);
  return f;
}

void EdgeSet::add_crossings(EdgeSet& f, std::span<const ForestShapeInput> shapes, const EdgeSetOptions& opt) {
  std::vector<CurveMesh> meshes;
  int next_id = 0;
  for (const ForestShapeInput& in : shapes) {
    meshes.push_back({in.mesh, in.shape});
    next_id = std::max(next_id, in.shape + 1);
  }
  auto segments = std::make_shared<std::vector<CrossingSegment>>(find_intersection_curves(meshes, &f.crossing_stats_));
  // A segment's group: its two shapes, in order. Segments are sorted by group (stable: the
  // deterministic order of find_intersection_curves within each).
  auto key = [](const CrossingSegment& c) {
    return std::pair(std::min(c.shape[0], c.shape[1]), std::max(c.shape[0], c.shape[1]));
  };
  std::stable_sort(segments->begin(), segments->end(),
                   [&](const CrossingSegment& a, const CrossingSegment& b) { return key(a) < key(b); });
  f.crossings_ = segments;
  for (size_t i = 0; i < segments->size();) {
    size_t j = i;
    while (j < segments->size() && key((*segments)[j]) == key((*segments)[i])) ++j;
    CrossingGroup g;
    g.id = next_id + int(f.crossing_groups_.size());
    std::tie(g.shape0, g.shape1) = key((*segments)[i]);
    g.segments = int(j - i);
    f.crossing_groups_.push_back(g);
    const int abase = int(f.always_.size());
    for (size_t k = i; k < j; ++k) {
      const CrossingSegment& c = (*segments)[k];
      Edge e;
      e.cls = EdgeClass::Intersection;
      e.shape = g.id;
      e.f0 = c.face[0];
      e.f1 = c.face[1];
      e.q0 = c.plane[0];
      e.q1 = c.plane[1];
      e.p0 = c.p0;
      e.p1 = c.p1;
      e.length = (c.p1 - c.p0).norm();
      e.angle = kPi;  // a jump of the full radiance, as a boundary edge's (always_edge_weight)
      e.crossing = &c;
      f.always_.push_back(e);
    }
    const int aend = int(f.always_.size());
    if (aend - abase > opt.always_tree_min_edges) {
      int depth = 0;
      build_topology(f.always_, abase, aend, g.id, /*always=*/true, opt, f.nodes_, f.always_roots_, depth);
    } else {
      for (int a = abase; a < aend; ++a) f.loose_always_edges_.push_back(a);
    }
    i = j;
  }
}

std::vector<ForestShapeInput> forest_inputs(const Scene& scene) {
  std::vector<ForestShapeInput> inputs;
  for (size_t s = 0; s < scene.shapes.size(); ++s) {
    const Shape& shape = scene.shapes[s];
    ForestShapeInput in;
    in.mesh = &shape.mesh;
    in.shape = int(s);
    in.face_normals = shape.face_normals || shape.mesh.normals.empty();
    const bool twosided =
        shape.bsdf >= 0 && shape.bsdf < int(scene.bsdfs.size()) && scene.bsdfs[size_t(shape.bsdf)].twosided;
    in.creases = twosided ? CreaseSet::All : CreaseSet::Concave;
    inputs.push_back(in);
  }
  return inputs;
}

size_t EdgeSet::memory_bytes() const {
  return nodes_.capacity() * sizeof(ForestNode) + edges_.capacity() * sizeof(Edge) +
         always_.capacity() * sizeof(Edge) + (crossings_ ? crossings_->capacity() * sizeof(CrossingSegment) : 0) +
         (roots_.capacity() + always_roots_.capacity() + loose_always_edges_.capacity()) * sizeof(int);
}

}  // namespace qsil::edgetree
