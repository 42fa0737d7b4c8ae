/// @file contour_set.cpp
/// See qsil/edgetree/contour_set.h.

#include "qsil/edgetree/contour_set.h"

#include "qsil/edgetree/mesh_edges.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace qsil::edgetree {

double arc_max_cos(const Vec3& x0, const Vec3& x1, const Vec3& p, const Vec3& axis) {
  const Vec3 w0 = x0 - p, w1 = x1 - p;
  const double l0 = w0.norm(), l1 = w1.norm();
  double best = std::max(l0 > 0 ? w0.dot(axis) / l0 : -1.0, l1 > 0 ? w1.dot(axis) / l1 : -1.0);
  // The arc's directions span the plane of w0, w1; the direction of that plane closest to the axis
  // is the axis projected onto it, which is on the arc when it lies between w0 and w1.
  const Vec3 n = w0.cross(w1);
  const double nn = n.squaredNorm();
  if (!(nn > 0)) return best;
  const Vec3 a = axis - (axis.dot(n) / nn) * n;
  const double la = a.norm();
  if (!(la > 0)) return best;
  if (w0.cross(a).dot(n) >= 0 && a.cross(w1).dot(n) >= 0) best = std::max(best, a.dot(axis) / la);
  return best;
}

bool ContourProbe::arc_in_core(const Vec3& x0, const Vec3& x1, const Vec3& p) const {
  // A linear map takes the arc (the central projection of the segment) to the arc of the mapped
  // segment, so the test is the circular one in the cosine domain.
  return arc_max_cos(to_cosine * (x0 - p), to_cosine * (x1 - p), Vec3::Zero(), Vec3::UnitZ()) >= cos_core;
}

ContourIndex ContourIndex::build(std::span<const ForestShapeInput> shapes, const EdgeSet& set) {
  ContourIndex index;
  int max_shape = -1;
  for (const ForestShapeInput& s : shapes) max_shape = std::max(max_shape, s.shape);
  index.meshes_.resize(size_t(max_shape + 1));
  for (const ForestShapeInput& in : shapes) {
    if (!in.mesh || in.mesh->num_triangles() == 0) continue;
    const TriangleMesh& tm = *in.mesh;
    MeshEdgeSet mes = build_mesh_edges(tm, in.shape, EdgeOptions{true});
    Mesh& m = index.meshes_[size_t(in.shape)];
    m.mesh = &tm;
    const Box3 box = tm.bounds();
    m.centre = box.center();
    for (const Vec3& v : tm.positions) m.radius = std::max(m.radius, (v - m.centre).norm());
    m.first_edge = index.total_edges_;
    index.total_edges_ += int(mes.edges.size());
    m.edges = std::move(mes.edges);
    m.entries.assign(m.edges.size(), nullptr);
    m.face_edges.resize(size_t(tm.num_triangles()));
    std::vector<int> degree(tm.positions.size() + 1, 0);
    for (int f = 0; f < tm.num_triangles(); ++f)
      for (int k = 0; k < 3; ++k)
        m.face_edges[size_t(f)][size_t(k)] =
            find_edge(m, tm.triangles[size_t(f)][k], tm.triangles[size_t(f)][(k + 1) % 3]);
    for (const MeshEdge& e : m.edges) {
      ++degree[size_t(e.v0)];
      ++degree[size_t(e.v1)];
    }
    m.vertex_begin.assign(tm.positions.size() + 1, 0);
    for (size_t v = 0; v < tm.positions.size(); ++v) m.vertex_begin[v + 1] = m.vertex_begin[v] + degree[v];
    m.vertex_edges.resize(size_t(m.vertex_begin.back()));
    std::vector<int> fill(m.vertex_begin.begin(), m.vertex_begin.end() - 1);
    for (size_t i = 0; i < m.edges.size(); ++i) {
      m.vertex_edges[size_t(fill[size_t(m.edges[i].v0)]++)] = int(i);
      m.vertex_edges[size_t(fill[size_t(m.edges[i].v1)]++)] = int(i);
    }
  }
  index.link(set);
  return index;
}

bool ContourIndex::refit(std::span<const ForestShapeInput> shapes, const EdgeSet& set) {
  for (const ForestShapeInput& in : shapes) {
    if (!in.mesh || in.mesh->num_triangles() == 0) continue;
    if (in.shape < 0 || in.shape >= int(meshes_.size())) return false;
    const Mesh& m = meshes_[size_t(in.shape)];
    if (m.mesh != in.mesh || m.face_edges.size() != in.mesh->triangles.size() ||
        m.vertex_begin.size() != in.mesh->positions.size() + 1)
      return false;
  }
  for (const ForestShapeInput& in : shapes) {
    if (!in.mesh || in.mesh->num_triangles() == 0) continue;
    const TriangleMesh& tm = *in.mesh;
    Mesh& m = meshes_[size_t(in.shape)];
    std::vector<Vec4> planes(size_t(tm.num_triangles()));
    for (int f = 0; f < tm.num_triangles(); ++f) planes[size_t(f)] = face_plane(tm, f);
    for (MeshEdge& e : m.edges) {
      e.length = (tm.positions[size_t(e.v1)] - tm.positions[size_t(e.v0)]).norm();
      e.q0 = planes[size_t(e.f0)];
      if (e.f1 >= 0) e.q1 = planes[size_t(e.f1)];
      if (e.cls == EdgeClass::Convex || e.cls == EdgeClass::Concave || e.cls == EdgeClass::Flat)
        e.cls = classify_interior_edge(tm, e);
    }
    const Box3 box = tm.bounds();
    m.centre = box.center();
    m.radius = 0;
    for (const Vec3& v : tm.positions) m.radius = std::max(m.radius, (v - m.centre).norm());
  }
  link(set);
  return true;
}

void ContourIndex::link(const EdgeSet& set) {
  for (Mesh& m : meshes_) m.entries.assign(m.edges.size(), nullptr);
  // One pass over the set; an edge in both arrays (a retired tree edge and its crease copy,
  // EdgeForest::refit) links to its always-candidate, the one that is a discontinuity.
  for (const auto* arr : {&set.edges(), &set.always_edges()})
    for (const Edge& fe : *arr) {
      if (fe.crossing || fe.shape < 0 || fe.shape >= int(meshes_.size())) continue;  // no mesh edge
      Mesh& m = meshes_[size_t(fe.shape)];
      if (!m.mesh) continue;
      // The edges at fe.v0 (CSR), a handful, rather than a search over all of them.
      const int lo = std::min(fe.v0, fe.v1), hi = std::max(fe.v0, fe.v1);
      if (lo < 0 || size_t(lo) + 1 >= m.vertex_begin.size()) continue;
      for (int k = m.vertex_begin[size_t(lo)]; k < m.vertex_begin[size_t(lo) + 1]; ++k) {
        const int i = m.vertex_edges[size_t(k)];
        if (m.edges[size_t(i)].v0 == lo && m.edges[size_t(i)].v1 == hi) {
          m.entries[size_t(i)] = &fe;
          break;
        }
      }
    }
}

int ContourIndex::find_edge(const Mesh& m, int a, int b) {
  const int lo = std::min(a, b), hi = std::max(a, b);
  auto it = std::lower_bound(
      m.edges.begin(), m.edges.end(), std::pair<int, int>(lo, hi),
      [](const MeshEdge& e, const std::pair<int, int>& k) { return e.v0 != k.first ? e.v0 < k.first : e.v1 < k.second; });
  return (it != m.edges.end() && it->v0 == lo && it->v1 == hi) ? int(it - m.edges.begin()) : -1;
}

namespace {

/// The edges a contour following has visited (numbered over all meshes): open addressing in a
/// table of 4 kMaxContourVisits slots (at most a quarter full), cleared in O(1) by a stamp.
class VisitedSet {
 public:
  void clear() {
    if (++stamp_ == 0) {  // wrapped around: old stamps could equal new ones
      slots_.fill({});
      stamp_ = 1;
    }
  }
  /// Adds `key`; false when it was there already.
  bool insert(std::uint32_t key) {
    for (std::uint32_t i = (key * 2654435761u) & (kSize - 1);; i = (i + 1) & (kSize - 1)) {
      Slot& s = slots_[i];
      if (s.stamp != stamp_) {
        s = {key, stamp_};
        return true;
      }
      if (s.key == key) return false;
    }
  }

 private:
  static constexpr std::uint32_t kSize = 4 * kMaxContourVisits;
  static_assert((kSize & (kSize - 1)) == 0, "a power of two");
  struct Slot {
    std::uint32_t key = 0, stamp = 0;
  };
  std::array<Slot, kSize> slots_{};
  std::uint32_t stamp_ = 0;
};

/// The buffers of a contour set's construction (EdgeChoiceScratch).
struct ContourBuffers {
  std::vector<std::pair<int, int>> seeds;  ///< (shape, edge)
  VisitedSet visited;
  std::vector<std::pair<int, int>> stack;
};

/// Walk directions: angles pi k / kContourWalks, k = 0 .. 2 kContourWalks - 1.
static_assert(kContourWalks == 4, "the tables below hold 8 directions");
constexpr double kWalkCos[8] = {1.0,  0.70710678118654757,  0.0, -0.70710678118654757,
                                -1.0, -0.70710678118654757, 0.0, 0.70710678118654757};
constexpr double kWalkSin[8] = {0.0, 0.70710678118654757,  1.0,  0.70710678118654757,
                                0.0, -0.70710678118654757, -1.0, -0.70710678118654757};
}  // namespace

void ContourIndex::contour_edges(const ContourProbe& probe, const Vec3& p, const std::vector<bool>* eligible,
                                 std::vector<const Edge*>& out, EdgeChoiceScratch* scratch) const {
  out.clear();
  EdgeChoiceScratch fallback;
  ContourBuffers& buffers = scratch_buffer<ContourBuffers>(scratch, fallback);
  const Vec4 ph(p.x(), p.y(), p.z(), 1.0);
  auto indexed = [&](int shape) {
    return shape >= 0 && shape < int(meshes_.size()) && meshes_[size_t(shape)].mesh &&
           (!eligible || (shape < int(eligible->size()) && (*eligible)[size_t(shape)]));
  };
  // An edge where the facing changes (or that has no second face to walk to): the edge set's own
  // silhouette predicate, on every mesh edge (flat and culled ones too).
  auto turns = [&](const MeshEdge& e) { return edge_is_silhouette(e, p); };

  // ---- 1. From each hit, walks across the faces the planes through its ray cut, to the first
  // silhouette.
  std::vector<std::pair<int, int>>& seeds = buffers.seeds;
  seeds.clear();
  for (int h = 0; h < probe.count; ++h) {
    const ContourHit& hit = probe.hits[size_t(h)];
    if (!indexed(hit.shape)) continue;
    const Mesh& m = meshes_[size_t(hit.shape)];
    if (hit.triangle < 0 || hit.triangle >= int(m.face_edges.size())) continue;
    const std::vector<Vec3>& x = m.mesh->positions;
    const Vec3 u0 = hit.dir.unitOrthogonal(), u1 = hit.dir.cross(u0);
    for (int k = 0; k < 2 * kContourWalks; ++k) {
      const Vec3 u = kWalkCos[k] * u0 + kWalkSin[k] * u1;  // walk direction, across the ray
      const Vec3 plane = hit.dir.cross(u);                 // normal of the walk's plane through p
      int f = hit.triangle, from = -1;
      for (int step = 0; step < kContourWalkSteps; ++step) {
        // The edge of f the plane leaves it through: the one other than the entry edge with its
        // endpoints on both sides; at the start, the one on the +u side of the hit point.
        int exit = -1;
        Vec3 c = Vec3::Zero();
        for (int ei : m.face_edges[size_t(f)]) {
          if (ei < 0 || ei == from) continue;
          const MeshEdge& e = m.edges[size_t(ei)];
          const double s0 = plane.dot(x[size_t(e.v0)] - p), s1 = plane.dot(x[size_t(e.v1)] - p);
          if ((s0 > 0) == (s1 > 0)) continue;
          const Vec3 ci = x[size_t(e.v0)] + (s0 / (s0 - s1)) * (x[size_t(e.v1)] - x[size_t(e.v0)]);
          if (from < 0 && !((ci - hit.point).dot(u) > 0)) continue;
          exit = ei;
          c = ci;
          break;
        }
        if (exit < 0) break;
        if (!probe.in_core(c, p)) break;  // left the core
        const MeshEdge& e = m.edges[size_t(exit)];
        if (turns(e)) {
          seeds.emplace_back(hit.shape, exit);
          break;
        }
        from = exit;
        f = e.f0 == f ? e.f1 : e.f0;
      }
    }
  }

  // ---- 2. Contour following: silhouette edges sharing a vertex, within the core.
  VisitedSet& visited = buffers.visited;
  visited.clear();
  std::vector<std::pair<int, int>>& stack = buffers.stack;
  stack.assign(seeds.begin(), seeds.end());
  int visits = 0;
  while (!stack.empty() && int(out.size()) < kMaxContourEdges && visits < kMaxContourVisits) {
    const std::pair<int, int> cur = stack.back();
    stack.pop_back();
    const Mesh& m = meshes_[size_t(cur.first)];
    if (!visited.insert(std::uint32_t(m.first_edge + cur.second))) continue;
    ++visits;
    const MeshEdge& e = m.edges[size_t(cur.second)];
    const std::vector<Vec3>& x = m.mesh->positions;
    if (!probe.arc_in_core(x[size_t(e.v0)], x[size_t(e.v1)], p)) continue;
    const Edge* entry = m.entries[size_t(cur.second)];
    if (entry && e.cls != EdgeClass::Concave && edge_is_silhouette(*entry, p)) out.push_back(entry);
    for (int v : {e.v0, e.v1})
      for (int j = m.vertex_begin[size_t(v)]; j < m.vertex_begin[size_t(v) + 1]; ++j) {
        const int ej = m.vertex_edges[size_t(j)];
        if (ej != cur.second && turns(m.edges[size_t(ej)])) stack.emplace_back(cur.first, ej);
      }
  }
}

bool ContourIndex::cone_meets_shapes(const Vec3& p, const Vec3& axis, double cos_half_angle,
                                     const std::vector<bool>* eligible) const {
  const double half = std::acos(std::clamp(cos_half_angle, -1.0, 1.0));
  for (size_t shape = 0; shape < meshes_.size(); ++shape) {
    const Mesh& m = meshes_[shape];
    if (!m.mesh || (eligible && (shape >= eligible->size() || !(*eligible)[shape]))) continue;
    const Vec3 d = m.centre - p;
    const double dist = d.norm();
    if (!(dist > m.radius)) return true;  // p inside the sphere (or a NaN): conservative
    // The sphere subtends asin(r / dist) about d; the cone reaches it iff the angle between the
    // axis and d is at most that plus the cone's half-angle.
    const double angle = std::acos(std::clamp(d.dot(axis) / dist, -1.0, 1.0));
    if (angle <= half + std::asin(m.radius / dist)) return true;
  }
  return false;
}

size_t ContourIndex::memory_bytes() const {
  size_t b = meshes_.size() * sizeof(Mesh);
  for (const Mesh& m : meshes_)
    b += m.face_edges.size() * sizeof(std::array<int, 3>) + m.edges.size() * sizeof(MeshEdge) +
         m.entries.size() * sizeof(const Edge*) + (m.vertex_begin.size() + m.vertex_edges.size()) * sizeof(int);
  return b;
}

}  // namespace qsil::edgetree
