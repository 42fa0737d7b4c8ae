/// @file edge_set.cpp
/// Edge extraction per shape and the top-down 4-wide SAH hierarchy [QSS 4.1]; see
/// qsil/edgetree/edge_set.h.

#include "qsil/edgetree/edge_set.h"

#include "qsil/fnv1a.h"
#include "sah_split.h"

#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <chrono>
#include <deque>
#include <tuple>

namespace qsil::edgetree {

namespace {

/// Hash of a mesh's triangles (a refit's check that the topology is the one built).
std::uint64_t triangle_hash(const TriangleMesh& mesh) {
  return fnv1a(mesh.triangles.data(), mesh.triangles.size() * sizeof(mesh.triangles[0]));
}

/// The crease rule of a shape: every non-flat edge of a flat-shaded one.
CreaseSet crease_rule(const ForestShapeInput& in) { return in.face_normals ? CreaseSet::All : in.creases; }

/// Whether an interior edge of class `cls` is a crease under rule `creases` (as
/// shape_always_edges decides).
bool is_crease_class(EdgeClass cls, CreaseSet creases) {
  return (cls == EdgeClass::Concave && creases != CreaseSet::None) ||
         (cls == EdgeClass::Convex && creases == CreaseSet::All);
}

/// B_p, L_w and L_w's smooth-crease part of node n over its edges in `edges` (the tree's array).
/// Retired edges (Edge::retired) are in B_p, as in the node's bound, but weigh nothing.
void node_extent(ForestNode& n, const std::vector<Edge>& edges) {
  const bool always = n.always();
  n.bp = Box3();
  n.lw = 0.0;
  n.lw_smooth = 0.0;
  for (int k = n.edge_begin; k < n.edge_end; ++k) {
    const Edge& e = edges[size_t(k)];
    n.bp.expand(e.p0);
    n.bp.expand(e.p1);
    if (e.retired) continue;
    n.lw += always ? always_edge_weight(e) : e.length * e.angle;
    if (e.smooth_crease && e.cls == EdgeClass::Concave) n.lw_smooth += always_edge_weight(e);
  }
}

/// B_p, L_w and L_w's smooth-crease part of inner node n from its children's, in child order
/// (the children come after n in `nodes` and have theirs already). Build and refit both take an
/// inner node's from its children, so a refit of unmoved vertices gives the build's numbers.
void node_extent_from_children(ForestNode& n, const std::vector<ForestNode>& nodes) {
  n.bp = Box3();
  n.lw = 0.0;
  n.lw_smooth = 0.0;
  for (int c = n.first; c < n.first + n.count; ++c) {
    const ForestNode& child = nodes[size_t(c)];
    n.bp.expand(child.bp);
    n.lw += child.lw;
    n.lw_smooth += child.lw_smooth;
  }
}

// Splits refs [b, e) into 2..4 groups: one binary SAH split, then each half again if it is
// larger than a leaf [QSS 4.1: three binary splits per level].
std::vector<std::pair<int, int>> split4(std::vector<EdgeBoxRef>& refs, int b, int e, const EdgeSetOptions& opt) {
  std::vector<std::pair<int, int>> out;
  const int m = b + sah_split(std::span(refs.data() + b, size_t(e - b)), opt.sah_buckets);
  for (auto [lo, hi] : {std::pair{b, m}, std::pair{m, e}}) {
    if (hi - lo > opt.leaf_size) {
      const int mm = lo + sah_split(std::span(refs.data() + lo, size_t(hi - lo)), opt.sah_buckets);
      out.push_back({lo, mm});
      out.push_back({mm, hi});
    } else {
      out.push_back({lo, hi});
    }
  }
  return out;
}

/// Reorders edges [ebase, ebase + order.size()) of `edges` in place so that position ebase + k
/// holds the edge that was at ebase + order[k].index (a permutation), following its cycles: no
/// copy of the range is made.
void permute_edges(std::vector<Edge>& edges, int ebase, const std::vector<EdgeBoxRef>& order) {
  const size_t n = order.size();
  std::vector<char> done(n, 0);
  for (size_t start = 0; start < n; ++start) {
    if (done[start]) continue;
    Edge held = std::move(edges[size_t(ebase) + start]);
    size_t j = start;
    while (true) {
      done[j] = 1;
      const size_t from = size_t(order[j].index);
      if (from == start) break;
      edges[size_t(ebase) + j] = std::move(edges[size_t(ebase) + from]);
      j = from;
    }
    edges[size_t(ebase) + j] = std::move(held);
  }
}

/// Edge idx of `set` as a forest edge, with its end points (world frame) from `mesh`.
Edge forest_edge(const MeshEdgeSet& set, const TriangleMesh& mesh, int idx) {
  Edge fe;
  static_cast<MeshEdge&>(fe) = set.edges[idx];
  fe.p0 = mesh.positions[fe.v0];
  fe.p1 = mesh.positions[fe.v1];
  return fe;
}

/// Top-down 4-wide topology over the edges of `refs` (their boxes, refs[k].index = k: the tree's
/// k-th edge, which will sit at position ebase + k of the tree's edge array once in leaf order),
/// appended to `nodes` breadth-first so that every level is a contiguous node range; the root is
/// discarded, its children become `roots`. Nodes of an always-candidate tree carry kNodeAlways. On
/// return refs is in leaf order: the edge that was k-th as given (k = refs[j].index) goes to
/// ebase + j; the nodes' B_p and L_w are not set (node_extents, once the edges are there). Returns the node range of
/// every level; `depth` receives the number of levels.
std::vector<std::pair<int, int>> build_levels(std::vector<EdgeBoxRef>& refs, int ebase, int shape, bool always,
                                              const EdgeSetOptions& opt, std::vector<ForestNode>& nodes,
                                              std::vector<int>& roots, int& depth) {
  std::vector<std::pair<int, int>> levels;
  depth = 0;
  const int n = int(refs.size());
  if (n == 0) return levels;
  const int nbase = int(nodes.size());
  // The splits order small records (EdgeBoxRef, positions relative to ebase), not the edges;
  // the nodes of one level cover disjoint ranges, so a level's splits run in parallel.
  std::vector<std::pair<int, int>> top;
  if (n <= opt.leaf_size)
    top.push_back({0, n});
  else
    top = split4(refs, 0, n, opt);
  auto add_node = [&](int b, int e, int parent, int d) {
    ForestNode node;
    node.edge_begin = ebase + b;
    node.edge_end = ebase + e;
    node.parent = parent;
    node.shape = shape;
    node.depth = std::uint16_t(d);
    if (always) node.flags |= kNodeAlways;
    if (e - b <= opt.leaf_size) {
      node.flags |= kNodeLeaf;
      node.first = ebase + b;
      node.count = e - b;
    }
    nodes.push_back(node);
  };
  for (auto [b, e] : top) {
    roots.push_back(int(nodes.size()));
    add_node(b, e, -1, 0);
  }
  int level_begin = nbase;
  std::vector<std::vector<std::pair<int, int>>> groups;
  while (level_begin < int(nodes.size())) {
    const int level_end = int(nodes.size());
    levels.push_back({level_begin, level_end});
    groups.assign(size_t(level_end - level_begin), {});
    tbb::parallel_for(level_begin, level_end, [&](int i) {
      const ForestNode& node = nodes[size_t(i)];
      if (!node.is_leaf())
        groups[size_t(i - level_begin)] = split4(refs, node.edge_begin - ebase, node.edge_end - ebase, opt);
    });
    for (int i = level_begin; i < level_end; ++i) {
      if (nodes[size_t(i)].is_leaf()) continue;
      const auto& g = groups[size_t(i - level_begin)];
      nodes[size_t(i)].first = int(nodes.size());
      nodes[size_t(i)].count = int(g.size());
      for (auto [b, e] : g) add_node(b, e, i, depth + 1);
    }
    level_begin = level_end;
    ++depth;
  }
  return levels;
}

/// B_p and L_w of the nodes of `levels` (build_levels), whose edges are in place in `edges`: the
/// leaves from their edges, then the inner nodes from their children, deepest level first; each
/// step in parallel.
void node_extents(const std::vector<std::pair<int, int>>& levels, std::vector<ForestNode>& nodes,
                  const std::vector<Edge>& edges) {
  if (levels.empty()) return;
  tbb::parallel_for(levels.front().first, levels.back().second, [&](int i) {
    if (nodes[size_t(i)].is_leaf()) node_extent(nodes[size_t(i)], edges);
  });
  for (auto level = levels.rbegin(); level != levels.rend(); ++level)
    tbb::parallel_for(level->first, level->second, [&](int i) {
      if (!nodes[size_t(i)].is_leaf()) node_extent_from_children(nodes[size_t(i)], nodes);
    });
}

/// build_levels over edges [ebase, eend) of `edges`, which it reorders in place into leaf order,
/// then node_extents: for edges already in their array (a refit's promoted creases, the
/// intersection curves). Returns the node range of every level; `depth` receives the number of
/// levels.
std::vector<std::pair<int, int>> build_topology(std::vector<Edge>& edges, int ebase, int eend, int shape, bool always,
                                                const EdgeSetOptions& opt, std::vector<ForestNode>& nodes,
                                                std::vector<int>& roots, int& depth) {
  depth = 0;
  if (eend <= ebase) return {};
  std::vector<EdgeBoxRef> refs(size_t(eend - ebase));
  tbb::parallel_for(0, eend - ebase, [&](int k) { refs[size_t(k)] = edge_box_ref(edges[size_t(ebase + k)], k); });
  const auto levels = build_levels(refs, ebase, shape, always, opt, nodes, roots, depth);
  permute_edges(edges, ebase, refs);
  node_extents(levels, nodes, edges);
  return levels;
}

/// The shape's edges set.edges[idx[k]] (k < idx.size()) as forest edges (forest_edge, and those
/// with crease[k] marked as creases of a shape smooth-shaded unless face_normals), appended to
/// `edges` (its capacity reserved) in tree order: as a tree over them (build_levels) when `tree`,
/// else in the order given. Each edge is written once, in its place, in parallel. Returns the
/// tree's levels (none without a tree); `depth` receives their number.
std::vector<std::pair<int, int>> append_tree_edges(const MeshEdgeSet& set, const TriangleMesh& mesh,
                                                   const std::vector<int>& idx, const std::vector<char>& crease,
                                                   bool face_normals, bool tree, int shape, bool always,
                                                   const EdgeSetOptions& opt, std::vector<Edge>& edges,
                                                   std::vector<ForestNode>& nodes, std::vector<int>& roots,
                                                   int& depth) {
  depth = 0;
  const int ebase = int(edges.size()), n = int(idx.size());
  std::vector<EdgeBoxRef> refs(static_cast<size_t>(n));
  tbb::parallel_for(0, n, [&](int k) {
    const MeshEdge& e = set.edges[size_t(idx[size_t(k)])];
    refs[size_t(k)] = edge_box_ref(mesh.positions[size_t(e.v0)], mesh.positions[size_t(e.v1)], k);
  });
  std::vector<std::pair<int, int>> levels;
  if (tree) levels = build_levels(refs, ebase, shape, always, opt, nodes, roots, depth);
  edges.resize(size_t(ebase + n));
  tbb::parallel_for(0, n, [&](int k) {
    const int from = refs[size_t(k)].index;
    Edge& e = edges[size_t(ebase + k)];
    e = forest_edge(set, mesh, idx[size_t(from)]);
    if (crease[size_t(from)]) {
      e.crease = true;
      e.smooth_crease = !face_normals;
    }
  });
  node_extents(levels, nodes, edges);
  return levels;
}

/// A shape's always-candidate edges, as indices into set.edges (`idx`) with a crease mark each
/// (`crease`): set.always (boundary, non-manifold, inconsistent), then the creases of `in` (all of
/// them for a flat-shaded shape), also marked in is_crease (one entry per edge of `set`) and
/// counted in st.creases.
void shape_always_edges(const ForestShapeInput& in, const MeshEdgeSet& set, std::vector<char>& is_crease,
                        ForestShapeStats& st, std::vector<int>& idx, std::vector<char>& crease) {
  const CreaseSet creases = crease_rule(in);
  idx.assign(set.always.begin(), set.always.end());
  crease.assign(idx.size(), 0);
  for (size_t k = 0; k < set.edges.size(); ++k) {
    if (is_crease_class(set.edges[k].cls, creases)) {
      is_crease[k] = 1;
      idx.push_back(int(k));
      crease.push_back(1);
      ++st.creases;
    }
  }
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
  // ---- the intersection curves, beside the shapes' trees (they read the meshes only; the trees'
  // serial steps leave a core idle), appended after them
  // (Declared after `f` and `crossings`, which it writes: if the shapes' loop throws, its
  // destructor cancels and waits for the task before they are destroyed. The task may run on
  // this thread inside the loop's parallel waits, so a shape's build_seconds can include it.)
  std::vector<CrossingSegment> crossings;
  tbb::task_group crossings_task;
  if (opt.intersection_curves) crossings_task.run([&] { crossings = find_crossings(shapes, f.crossing_stats_); });
  // ---- every shape's edges first, so that the shared arrays are sized once: appending a large
  // shape's edges and then a small one's would copy the large one's. The price: in a scene of
  // several shapes, the later shapes' edge sets are held while the earlier ones' trees are built.
  std::vector<MeshEdgeSet> sets(shapes.size());
  std::vector<double> edge_seconds(shapes.size());
  size_t always_total = 0, kept_total = 0;
  for (size_t i = 0; i < shapes.size(); ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    sets[i] = build_mesh_edges(*shapes[i].mesh, shapes[i].shape, opt.edges);
    edge_seconds[i] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const CreaseSet creases = crease_rule(shapes[i]);
    always_total += sets[i].always.size();
    for (const MeshEdge& e : sets[i].edges) always_total += is_crease_class(e.cls, creases) ? 1 : 0;
    if (!shapes[i].face_normals)
      for (int idx : sets[i].kept) kept_total += is_crease_class(sets[i].edges[size_t(idx)].cls, creases) ? 0 : 1;
  }
  f.always_.reserve(always_total);
  f.edges_.reserve(kept_total);
  for (size_t i = 0; i < shapes.size(); ++i) {
    const ForestShapeInput& in = shapes[i];
    const auto t0 = std::chrono::steady_clock::now();
    ForestShapeStats st;
    st.shape = in.shape;
    const TriangleMesh& mesh = *in.mesh;
    const MeshEdgeSet set = std::move(sets[i]);
    st.edge_counts = set.counts;
    st.edges_total = int(set.edges.size());
    st.edges_kept = int(set.kept.size());
    // ---- always-candidate edges: boundary, non-manifold, inconsistent, and the creases
    std::vector<char> is_crease(set.edges.size(), 0);
    std::vector<int> idx;
    std::vector<char> crease;
    shape_always_edges(in, set, is_crease, st, idx, crease);
    st.edges_always = int(idx.size());
    const int abase = int(f.always_.size());
    const bool always_tree = st.edges_always > opt.always_tree_min_edges;
    const int n0 = int(f.nodes_.size());
    int always_depth = 0;
    append_tree_edges(set, mesh, idx, crease, in.face_normals, always_tree, in.shape, /*always=*/true, opt, f.always_,
                      f.nodes_, f.always_roots_, always_depth);
    if (always_tree)
      st.always_nodes = int(f.nodes_.size()) - n0;
    else
      for (int i = abase; i < int(f.always_.size()); ++i) f.loose_always_edges_.push_back(i);

    // ---- silhouette tree edges: the kept edges that are not creases (a flat-shaded shape has
    // none: its crease branch covers silhouettes too); their topology and B_p, L_w of every node
    idx.clear();
    if (!in.face_normals)
      for (int k : set.kept)
        if (!is_crease[size_t(k)]) idx.push_back(k);
    crease.assign(idx.size(), 0);
    st.edges_kept = int(idx.size());
    const int nbase = int(f.nodes_.size());
    int depth = 0;
    const size_t roots_before = f.roots_.size();
    ShapeTree tree;
    tree.levels = append_tree_edges(set, mesh, idx, crease, in.face_normals, /*tree=*/true, in.shape,
                                    /*always=*/false, opt, f.edges_, f.nodes_, f.roots_, depth);
    f.trees_.push_back(std::move(tree));
    st.roots = int(f.roots_.size() - roots_before);
    st.depth = depth;
    count_nodes(f.nodes_, nbase, st);
    st.build_seconds = edge_seconds[i] + std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    f.stats_.push_back(st);
    // ---- what a refit needs: the topology's fingerprint and the edges in no array
    f.shape_records_.push_back(
        {in.shape, mesh.num_vertices(), mesh.num_triangles(), triangle_hash(mesh), in.face_normals, in.creases});
    // Edges in no array: flat ones, and concave ones culled (no crease rule, keep_concave off).
    for (const MeshEdge& e : set.edges)
      if (e.cls == EdgeClass::Flat ||
          (e.cls == EdgeClass::Concave && crease_rule(in) == CreaseSet::None && !opt.edges.keep_concave))
        f.flat_edges_.push_back({e.v0, e.v1, e.f0, e.f1, e.shape});
  }
  f.options_ = opt;
  f.shapes_nodes_end_ = f.nodes_.size();
  f.shapes_always_end_ = f.always_.size();
  f.shapes_always_roots_end_ = f.always_roots_.size();
  f.shapes_loose_end_ = f.loose_always_edges_.size();
  crossings_task.wait();
  if (opt.intersection_curves) add_crossings(f, shapes, std::move(crossings), opt);
  return f;
}

bool EdgeSet::refit_input_matches(std::span<const ForestShapeInput> shapes, RefitReport& report) const {
  // ---- the input must be the shapes built, with the same topology and crease rules
  if (shapes.size() != shape_records_.size()) {
    report.reason = std::to_string(shapes.size()) + " shapes given, " + std::to_string(shape_records_.size()) + " built";
    return false;
  }
  for (size_t i = 0; i < shapes.size(); ++i) {
    const ShapeRecord& r = shape_records_[i];
    const ForestShapeInput& in = shapes[i];
    const std::string name = "shape " + std::to_string(r.shape) + ": ";
    if (in.shape != r.shape || !in.mesh) {
      report.reason = name + "not given in the place it was built";
      return false;
    }
    if (in.mesh->num_vertices() != r.vertices || in.mesh->num_triangles() != r.triangles ||
        triangle_hash(*in.mesh) != r.triangle_hash) {
      report.reason = name + "its triangles changed (a refit keeps the topology)";
      return false;
    }
    if (in.face_normals != r.face_normals || in.creases != r.creases) {
      report.reason = name + "its crease rule changed";
      return false;
    }
  }
  return true;
}

void EdgeSet::refit_edges(std::span<const ForestShapeInput> shapes, RefitReport& report) {
  int max_shape = 0;
  for (const ForestShapeInput& in : shapes) max_shape = std::max(max_shape, in.shape);
  std::vector<const ForestShapeInput*> input(size_t(max_shape) + 1, nullptr);
  std::vector<size_t> place(size_t(max_shape) + 1, 0);
  for (size_t i = 0; i < shapes.size(); ++i) {
    input[size_t(shapes[i].shape)] = &shapes[i];
    place[size_t(shapes[i].shape)] = i;
  }
  // ---- face planes of the moved meshes
  std::vector<std::vector<Vec4>> planes(input.size());
  for (const ForestShapeInput& in : shapes) {
    std::vector<Vec4>& pl = planes[size_t(in.shape)];
    pl.resize(size_t(in.mesh->num_triangles()));
    tbb::parallel_for(0, in.mesh->num_triangles(), [&](int f) { pl[size_t(f)] = face_plane(*in.mesh, f); });
  }
  // ---- back to the shapes' own arrays: promoted creases and crossings are made anew below
  nodes_.resize(shapes_nodes_end_);
  always_.resize(shapes_always_end_);
  always_roots_.resize(shapes_always_roots_end_);
  loose_always_edges_.resize(shapes_loose_end_);
  crossing_groups_.clear();
  crossings_.reset();
  crossing_stats_ = {};
  // ---- every edge to its new place and class; tree edges now creases are retired
  auto move_edge = [&](MeshEdge& e, Vec3* p0, Vec3* p1) {
    const TriangleMesh& mesh = *input[size_t(e.shape)]->mesh;
    const std::vector<Vec4>& pl = planes[size_t(e.shape)];
    const Vec3 a = mesh.positions[size_t(e.v0)], b = mesh.positions[size_t(e.v1)];
    if (p0) *p0 = a;
    if (p1) *p1 = b;
    e.length = (b - a).norm();
    e.q0 = pl[size_t(e.f0)];
    if (e.f1 >= 0) e.q1 = pl[size_t(e.f1)];
    if (e.cls == EdgeClass::Convex || e.cls == EdgeClass::Concave || e.cls == EdgeClass::Flat)
      e.cls = classify_interior_edge(mesh, e);
  };
  std::vector<std::uint8_t> retired(edges_.size());  // the flags again, a byte each: scanned below
  tbb::parallel_for(size_t(0), edges_.size(), [&](size_t k) {
    Edge& e = edges_[k];
    move_edge(e, &e.p0, &e.p1);
    e.retired = is_crease_class(e.cls, crease_rule(*input[size_t(e.shape)]));
    retired[k] = e.retired;
  });
  tbb::parallel_for(size_t(0), always_.size(), [&](size_t k) { move_edge(always_[k], &always_[k].p0, &always_[k].p1); });
  report.edges = int(edges_.size() + always_.size());
  // ---- the promoted creases, per shape in input order (deterministic: array order)
  std::vector<std::vector<Edge>> promoted(shapes.size());
  for (size_t k = 0; k < edges_.size(); ++k)
    if (retired[k]) {
      const Edge& e = edges_[k];
      Edge c = e;
      c.retired = false;
      c.crease = true;
      c.smooth_crease = !input[size_t(e.shape)]->face_normals;
      promoted[place[size_t(e.shape)]].push_back(c);
      ++report.retired;
    }
  for (const FlatEdge& fe : flat_edges_) {
    Edge e;
    e.v0 = fe.v0;
    e.v1 = fe.v1;
    e.f0 = fe.f0;
    e.f1 = fe.f1;
    e.shape = fe.shape;
    e.cls = EdgeClass::Flat;
    move_edge(e, &e.p0, &e.p1);
    const ForestShapeInput& in = *input[size_t(fe.shape)];
    // Bent (or turned convex) now: a crease (the crease branch covers a silhouette too); a
    // concave edge that is no crease is culled as the build culls it.
    if (e.cls == EdgeClass::Flat || (e.cls == EdgeClass::Concave && crease_rule(in) == CreaseSet::None &&
                                     !options_.edges.keep_concave))
      continue;
    e.crease = true;
    e.smooth_crease = !in.face_normals;
    promoted[place[size_t(fe.shape)]].push_back(e);
    ++report.unflattened;
  }
  for (size_t i = 0; i < shapes.size(); ++i) {
    if (promoted[i].empty()) continue;
    const int abase = int(always_.size());
    always_.insert(always_.end(), promoted[i].begin(), promoted[i].end());
    const int aend = int(always_.size());
    if (aend - abase > options_.always_tree_min_edges) {
      int depth = 0;
      build_topology(always_, abase, aend, shapes[i].shape, /*always=*/true, options_, nodes_, always_roots_, depth);
    } else {
      for (int a = abase; a < aend; ++a) loose_always_edges_.push_back(a);
    }
  }
  // ---- B_p and L_w of the shapes' nodes (the promoted trees have theirs from build_topology),
  // bottom-up: the leaves from their edges (in parallel: they read their own edges only), then an
  // inner node from its children (larger indices)
  tbb::parallel_for(size_t(0), shapes_nodes_end_, [&](size_t i) {
    ForestNode& n = nodes_[i];
    if (n.is_leaf()) node_extent(n, n.always() ? always_ : edges_);
  });
  for (size_t i = shapes_nodes_end_; i-- > 0;)
    if (!nodes_[i].is_leaf()) node_extent_from_children(nodes_[i], nodes_);
}

std::vector<CrossingSegment> EdgeSet::find_crossings(std::span<const ForestShapeInput> shapes,
                                                     IntersectionCurveStats& stats, CandidatePairCache* cache) {
  std::vector<CurveMesh> meshes;
  for (const ForestShapeInput& in : shapes) meshes.push_back({in.mesh, in.shape});
  return find_intersection_curves(meshes, &stats, cache);
}

void EdgeSet::add_crossings(EdgeSet& f, std::span<const ForestShapeInput> shapes, std::vector<CrossingSegment> found,
                            const EdgeSetOptions& opt) {
  int next_id = 0;
  for (const ForestShapeInput& in : shapes) next_id = std::max(next_id, in.shape + 1);
  auto segments = std::make_shared<std::vector<CrossingSegment>>(std::move(found));
  f.always_.reserve(f.always_.size() + segments->size());
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
         flat_edges_.capacity() * sizeof(FlatEdge) + always_.capacity() * sizeof(Edge) +
         (crossings_ ? crossings_->capacity() * sizeof(CrossingSegment) : 0) +
         (roots_.capacity() + always_roots_.capacity() + loose_always_edges_.capacity()) * sizeof(int) +
         pair_cache_.memory_bytes();
}

}  // namespace qsil::edgetree
