/// @file vsphere_tree.cpp
/// See vsphere_tree.h.

#include "qsil/edgetree/vsphere_tree.h"

#include "qsil/check.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <numeric>

namespace qsil::edgetree {

Vec3 hough_point(const Vec4& q, const Vec3& o) {
  const Vec3 n = q.head<3>();
  return -n * (n.dot(o) + q[3]);
}

bool vsphere_box_may_have_silhouette(const Box3& hb, double world_scale, const Vec3& p, const Vec3& o, VSphereTest test) {
  if (hb.empty()) return false;
  const Vec3 V = p - o;
  const Vec3 c = 0.5 * V;
  const double r2 = 0.25 * V.squaredNorm();
  // Squared min and max distance of the box to the centre, per axis.
  double dmin2 = 0, dmax2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double lo = hb.lo[k] - c[k], hi = hb.hi[k] - c[k];
    if (lo > 0)
      dmin2 += lo * lo;
    else if (hi < 0)
      dmin2 += hi * hi;
    dmax2 += std::max(lo * lo, hi * hi);
  }
  // min/max over the box of g(h) = |h|^2 - h.V are dmin2 - r2 and dmax2 - r2. Tolerance: g is
  // -d (q.[p,1]); the ground truth q.[p,1] rounds at ~eps (|p| + |x0|), h at ~eps (|o| + |x0|).
  const double hmax = std::max(hb.lo.norm(), hb.hi.norm());
  const double L = world_scale + p.cwiseAbs().maxCoeff() + o.cwiseAbs().maxCoeff() + V.norm() + hmax;
  const double tol = kVSphereTol * L * (hmax + 1e-6 * L);
  if (!(dmin2 - r2 <= tol)) return std::isnan(dmin2 - r2);  // the box lies outside the sphere
  if (test == VSphereTest::Solid) return true;
  return !(dmax2 - r2 < -tol);  // hollow: reject a box strictly inside the sphere
}

namespace {

/// Spreads the low 10 bits of x so that bit i lands at bit 6i (for 6D interleaving).
std::uint64_t spread6(std::uint64_t x) {
  std::uint64_t r = 0;
  for (int i = 0; i < 10; ++i) r |= ((x >> i) & 1u) << (6 * i);
  return r;
}

/// Spreads the low 21 bits of x so that bit i lands at bit 3i.
std::uint64_t spread3(std::uint64_t x) {
  std::uint64_t r = 0;
  for (int i = 0; i < 21; ++i) r |= ((x >> i) & 1u) << (3 * i);
  return r;
}

/// Quantises x in [lo, hi] to [0, 2^bits - 1].
std::uint64_t quantise(double x, double lo, double hi, int bits) {
  const double maxv = double((std::uint64_t(1) << bits) - 1);
  const double t = hi > lo ? (x - lo) / (hi - lo) : 0.5;
  return std::uint64_t(std::clamp(t, 0.0, 1.0) * maxv);
}

struct BuildItem {
  std::uint64_t code = 0;
  const Edge* edge = nullptr;
  Vec3 h0 = Vec3::Zero(), h1 = Vec3::Zero();
};

struct Builder {
  std::vector<VSphereNode>& nodes;
  std::vector<const Edge*>& edges;
  std::vector<BuildItem>& items;
  int shape;
  bool hough;

  /// Builds the subtree over items [b, e) and returns its node index (preorder layout).
  int build(int b, int e) {
    const int id = int(nodes.size());
    nodes.emplace_back();
    nodes[size_t(id)].shape = shape;
    nodes[size_t(id)].hough = hough;
    if (e - b == 1) {
      const BuildItem& it = items[size_t(b)];
      VSphereNode& n = nodes[size_t(id)];
      n.edge = int(edges.size());
      edges.push_back(it.edge);
      n.bp.expand(it.edge->p0);
      n.bp.expand(it.edge->p1);
      if (hough) {
        n.bh.expand(it.h0);
        n.bh.expand(it.h1);
      }
      n.lw = it.edge->length * it.edge->angle;
      return id;
    }
    // Split at the highest bit in which the first and last (sorted) codes differ.
    int mid = b + (e - b) / 2;
    const std::uint64_t diff = items[size_t(b)].code ^ items[size_t(e - 1)].code;
    if (diff != 0) {
      const int bit = 63 - std::countl_zero(diff);
      const std::uint64_t mask = std::uint64_t(1) << bit;
      // First index whose code has the bit set (codes are sorted, the prefix above it is shared).
      int lo = b, hi = e - 1;
      while (lo < hi) {
        const int m = lo + (hi - lo) / 2;
        if (items[size_t(m)].code & mask)
          hi = m;
        else
          lo = m + 1;
      }
      mid = lo;
    }
    const int c0 = build(b, mid);
    const int c1 = build(mid, e);
    VSphereNode& n = nodes[size_t(id)];
    n.child[0] = c0;
    n.child[1] = c1;
    for (int c : {c0, c1}) {
      const VSphereNode& ch = nodes[size_t(c)];
      n.bp.expand(ch.bp);
      if (hough) n.bh.expand(ch.bh);
      n.lw += ch.lw;
    }
    return id;
  }
};

}  // namespace

VSphereTree VSphereTree::build(const EdgeSet& set, const Vec3& o) {
  VSphereTree t;
  t.origin_ = o;
  int num_shapes = 0;
  for (const Edge& e : set.edges()) num_shapes = std::max(num_shapes, e.shape + 1);
  for (const Edge& e : set.always_edges()) num_shapes = std::max(num_shapes, e.shape + 1);
  std::vector<std::vector<const Edge*>> plain(static_cast<size_t>(num_shapes)),
      hough(static_cast<size_t>(num_shapes));
  for (const Edge& e : set.edges()) (edge_is_silhouette(e, o) ? plain : hough)[size_t(e.shape)].push_back(&e);
  // Creases and intersection-curve segments are candidates for every point (no v-sphere test
  // applies): the plain BVH.
  for (const Edge& e : set.always_edges())
    if (e.crease || e.crossing) plain[size_t(e.shape)].push_back(&e);
  std::vector<BuildItem> items;
  for (int pass = 0; pass < 2; ++pass) {  // plain trees first: edges_[0, plain_edges_) are theirs
    for (int s = 0; s < num_shapes; ++s) {
      const bool is_hough = pass == 1;
      const auto& list = is_hough ? hough[size_t(s)] : plain[size_t(s)];
      if (list.empty()) continue;
      // ---- 6D (or 3D) points and their bounds.
      items.assign(list.size(), {});
      Box3 bm, bhh;
      for (size_t i = 0; i < list.size(); ++i) {
        BuildItem& it = items[i];
        it.edge = list[i];
        bm.expand(0.5 * (it.edge->p0 + it.edge->p1));
        if (is_hough) {
          it.h0 = hough_point(it.edge->q0, o);
          // A one-face edge would use the opposite plane (n1 = -n0); tree edges have two faces.
          it.h1 = it.edge->f1 >= 0 ? hough_point(it.edge->q1, o) : Vec3(-it.h0);
          bhh.expand(0.5 * (it.h0 + it.h1));
        }
      }
      // ---- Morton codes.
      for (BuildItem& it : items) {
        const Vec3 m = 0.5 * (it.edge->p0 + it.edge->p1);
        if (is_hough) {
          const Vec3 h = 0.5 * (it.h0 + it.h1);
          std::uint64_t code = 0;
          for (int k = 0; k < 3; ++k) {
            code |= spread6(quantise(m[k], bm.lo[k], bm.hi[k], 10)) << k;
            code |= spread6(quantise(h[k], bhh.lo[k], bhh.hi[k], 10)) << (3 + k);
          }
          it.code = code;
        } else {
          std::uint64_t code = 0;
          for (int k = 0; k < 3; ++k) code |= spread3(quantise(m[k], bm.lo[k], bm.hi[k], 21)) << k;
          it.code = code;
        }
      }
      std::sort(items.begin(), items.end(), [](const BuildItem& a, const BuildItem& b) { return a.code < b.code; });
      Builder builder{t.nodes_, t.edges_, items, s, is_hough};
      const int root = builder.build(0, int(items.size()));
      t.roots_.push_back({root, s, is_hough});
      if (!is_hough) t.plain_edges_ += int(list.size());
    }
  }
  return t;
}

bool VSphereTree::may_have_silhouette(int i, const Vec3& p, VSphereTest test) const {
  const VSphereNode& n = nodes_[size_t(i)];
  if (!n.hough) return true;
  return vsphere_box_may_have_silhouette(n.bh, n.bp.max_abs(), p, origin_, test);
}

size_t VSphereTree::memory_bytes() const {
  return nodes_.size() * sizeof(VSphereNode) + roots_.size() * sizeof(VSphereRoot) +
         edges_.size() * sizeof(const Edge*);
}

}  // namespace qsil::edgetree
