/// @file edge_forest.cpp
/// Forest topology (top-down 4-wide SAH) and parallel node fitting [QSS 4.1-4.4].

#include "edgetree/edge_forest.h"

#include "edgetree/sah_split.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <deque>

namespace qsil::edgetree {

namespace {

// Splits [b, e) into 2..4 groups: one binary SAH split, then each half again if it is larger
// than a leaf [QSS 4.1: three binary splits per level].
std::vector<std::pair<int, int>> split4(std::vector<ForestEdge>& edges, int b, int e,
                                        const ForestOptions& opt) {
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

// Fits one inner node from its edge range; `face_planes` are the shape's face planes.
NodeFit fit_range(const std::vector<ForestEdge>& edges, const std::vector<Vec4>& face_planes,
                  const ForestNode& n, const NodeFit* parent, const NodeFitOptions& opt) {
  // Unique face planes of the patch (faces identified by index within the shape).
  std::vector<int> faces;
  faces.reserve(size_t(2) * (n.edge_end - n.edge_begin));
  std::vector<Wedge> wedges;
  wedges.reserve(size_t(n.edge_end - n.edge_begin));
  for (int i = n.edge_begin; i < n.edge_end; ++i) {
    const ForestEdge& e = edges[i];
    faces.push_back(e.f0);
    faces.push_back(e.f1);
    wedges.push_back({e.q0, e.q1});
  }
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  std::vector<Vec4> planes;
  planes.reserve(faces.size());
  for (int fi : faces) planes.push_back(face_planes[fi]);
  return fit_node(planes, wedges, n.bp, parent, opt);
}

}  // namespace

EdgeForest EdgeForest::build(std::span<const ForestShapeInput> shapes, const ForestOptions& options) {
  EdgeForest f;
  ForestOptions opt = options;
  opt.leaf_size = std::clamp(opt.leaf_size, 1, 4);
  for (const ForestShapeInput& in : shapes) {
    const auto t0 = std::chrono::steady_clock::now();
    ForestShapeStats st;
    st.shape = in.shape;
    const TriangleMesh& mesh = *in.mesh;

    // ---- edges
    const MeshEdgeSet set = build_mesh_edges(mesh, in.shape, opt.edges);
    st.edge_counts = set.counts;
    st.edges_total = int(set.edges.size());
    st.edges_kept = int(set.kept.size());
    st.edges_always = int(set.always.size());
    auto make = [&](int idx) {
      ForestEdge fe;
      static_cast<MeshEdge&>(fe) = set.edges[idx];
      fe.p0 = mesh.positions[fe.v0];
      fe.p1 = mesh.positions[fe.v1];
      return fe;
    };
    for (int idx : set.always) f.always_.push_back(make(idx));
    const int ebase = int(f.edges_.size());
    if (in.face_normals) {
      // Creases: every edge between two faces that are not coplanar (convex and concave alike).
      for (size_t idx = 0; idx < set.edges.size(); ++idx) {
        const EdgeClass cls = set.edges[idx].cls;
        if (cls == EdgeClass::Convex || cls == EdgeClass::Concave) {
          f.always_.push_back(make(int(idx)));
          f.always_.back().crease = true;
          ++st.edges_always;
        }
      }
      st.edges_kept = 0;
    } else {
      for (int idx : set.kept) f.edges_.push_back(make(idx));
    }
    const int eend = int(f.edges_.size());

    // ---- topology: breadth-first, so every level is a contiguous node range
    const int nbase = int(f.nodes_.size());
    const int bbase = int(f.bounds_.size());
    std::vector<std::pair<int, int>> levels;  // node ranges per depth
    if (eend > ebase) {
      std::vector<std::pair<int, int>> top;
      if (eend - ebase <= opt.leaf_size) top.push_back({ebase, eend});
      else top = split4(f.edges_, ebase, eend, opt);
      auto add_node = [&](int b, int e, int parent, int depth) {
        ForestNode n;
        n.edge_begin = b;
        n.edge_end = e;
        n.parent = parent;
        n.shape = in.shape;
        n.depth = std::uint16_t(depth);
        if (e - b <= opt.leaf_size) {
          n.flags |= kNodeLeaf;
          n.first = b;
          n.count = e - b;
        }
        f.nodes_.push_back(n);
      };
      for (auto [b, e] : top) {
        f.roots_.push_back(int(f.nodes_.size()));
        add_node(b, e, -1, 0);
      }
      st.roots = int(top.size());
      int level_begin = nbase;
      int depth = 0;
      while (level_begin < int(f.nodes_.size())) {
        const int level_end = int(f.nodes_.size());
        levels.push_back({level_begin, level_end});
        for (int i = level_begin; i < level_end; ++i) {
          if (f.nodes_[i].is_leaf()) continue;
          const auto groups = split4(f.edges_, f.nodes_[i].edge_begin, f.nodes_[i].edge_end, opt);
          f.nodes_[i].first = int(f.nodes_.size());
          f.nodes_[i].count = int(groups.size());
          f.nodes_[i].bound = int(f.bounds_.size());
          f.bounds_.emplace_back();
          for (auto [b, e] : groups) add_node(b, e, i, depth + 1);
        }
        level_begin = level_end;
        ++depth;
      }
      st.depth = depth;
    }

    // ---- B_p, L_w for every node (edges are in final order now), in parallel
    const int nend = int(f.nodes_.size());
    tbb::parallel_for(nbase, nend, [&](int i) {
      ForestNode& n = f.nodes_[i];
      for (int k = n.edge_begin; k < n.edge_end; ++k) {
        n.bp.expand(f.edges_[k].p0);
        n.bp.expand(f.edges_[k].p1);
        n.lw += f.edges_[k].length * f.edges_[k].angle;
      }
    });

    // ---- fit inner nodes level by level (parents first, for inheritance)
    std::vector<NodeFit> fits(f.bounds_.size() - bbase);
    for (auto [lb, le] : levels) {
      tbb::parallel_for(lb, le, [&](int i) {
        ForestNode& n = f.nodes_[i];
        if (n.is_leaf()) return;
        const NodeFit* parent =
            n.parent >= 0 ? &fits[f.nodes_[n.parent].bound - bbase] : nullptr;
        NodeFit fit = fit_range(f.edges_, set.face_planes, n, parent, opt.fit);
        n.flags |= fit.flags;
        f.bounds_[n.bound] = fit.bound;
        fits[n.bound - bbase] = std::move(fit);
      });
    }

    // ---- statistics
    for (int i = nbase; i < nend; ++i) {
      const ForestNode& n = f.nodes_[i];
      st.nodes++;
      if (n.is_leaf()) {
        st.leaves++;
        continue;
      }
      st.inner_nodes++;
      if (n.flags & kNodeUnrejectable) st.unrejectable++;
      else if (n.flags & kNodeBoxOnly) st.box_only++;
      if (n.flags & kNodeInherited) st.inherited++;
      if (n.flags & kNodeUsedLp) st.used_lp++;
    }
    st.build_seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    f.stats_.push_back(st);
  }
  return f;
}

size_t EdgeForest::memory_bytes() const {
  return nodes_.capacity() * sizeof(ForestNode) + bounds_.capacity() * sizeof(NodeBound) +
         edges_.capacity() * sizeof(ForestEdge) + always_.capacity() * sizeof(ForestEdge) +
         roots_.capacity() * sizeof(int);
}

}  // namespace qsil::edgetree
