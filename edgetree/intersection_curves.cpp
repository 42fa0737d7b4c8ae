/// @file intersection_curves.cpp
/// Crossing segments of triangle meshes; see qsil/edgetree/intersection_curves.h. The only file
/// that includes CGAL (its exact orientation predicate).

#include "qsil/edgetree/intersection_curves.h"

#include "qsil/check.h"
#include "qsil/ray_tracer.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <unsupported/Eigen/AutoDiff>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <tuple>
#include <type_traits>

namespace qsil::edgetree {

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;

/// Sign of det[b - a, c - a, x - a] = sign of ((b - a) x (c - a)) . (x - a): +1 where x lies on
/// the side the counter-clockwise normal of (a, b, c) points to. Exact: a floating-point filter
/// (Shewchuk 1997, orient3d's first stage: error bound (7 + 56 eps) eps times the permanent), and
/// CGAL's exact predicate where the filter cannot decide.
int orientation(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& x) {
  const double adx = b.x() - a.x(), ady = b.y() - a.y(), adz = b.z() - a.z();
  const double bdx = c.x() - a.x(), bdy = c.y() - a.y(), bdz = c.z() - a.z();
  const double cdx = x.x() - a.x(), cdy = x.y() - a.y(), cdz = x.z() - a.z();
  const double det = adx * (bdy * cdz - bdz * cdy) + bdx * (cdy * adz - cdz * ady) + cdx * (ady * bdz - adz * bdy);
  const double permanent = std::abs(adx) * (std::abs(bdy * cdz) + std::abs(bdz * cdy)) +
                           std::abs(bdx) * (std::abs(cdy * adz) + std::abs(cdz * ady)) +
                           std::abs(cdx) * (std::abs(ady * bdz) + std::abs(adz * bdy));
  constexpr double eps = std::numeric_limits<double>::epsilon() / 2;  // unit roundoff
  const double bound = (7.0 + 56.0 * eps) * eps * permanent;
  if (std::isfinite(det) && std::isfinite(permanent)) {
    if (det > bound) return 1;
    if (det < -bound) return -1;
  }
  const auto o = CGAL::orientation(Kernel::Point_3(a.x(), a.y(), a.z()), Kernel::Point_3(b.x(), b.y(), b.z()),
                                   Kernel::Point_3(c.x(), c.y(), c.z()), Kernel::Point_3(x.x(), x.y(), x.z()));
  return o == CGAL::POSITIVE ? 1 : (o == CGAL::NEGATIVE ? -1 : 0);
}

/// One triangle of a pair: its vertices and where they come from.
struct Tri {
  std::array<Vec3, 3> x;
  std::array<VertexRef, 3> ref;
};

/// How an end of a triangle's interval on the planes' common line is made: the crossing of edge
/// (i, j) of triangle `self` (0: A, 1: B) with the other's plane, or (j < 0) its vertex i, shared.
struct EndRule {
  int self = 0, i = 0, j = -1;
};

using AD = Eigen::AutoDiffScalar<Eigen::Matrix<double, 15, 1>>;
using Vec3AD = Eigen::Matrix<AD, 3, 1>;

Vec3AD variable(const Vec3& x, int slot) {
  Vec3AD v;
  for (int k = 0; k < 3; ++k) v[k] = AD(x[k], 15, 3 * slot + k);
  return v;
}

/// The edge (i, j) of rule.self's triangle in a fixed order (by vertex), so that the two
/// triangles of an edge make the same point to the last bit and a curve's segments meet exactly.
std::pair<int, int> ordered_edge(const EndRule& rule, const Tri& self) {
  int i = rule.i, j = rule.j;
  if (std::pair(self.ref[size_t(j)].shape, self.ref[size_t(j)].vertex) <
      std::pair(self.ref[size_t(i)].shape, self.ref[size_t(i)].vertex))
    std::swap(i, j);
  return {i, j};
}

/// The point X = a + s (b - a), s = n.(c0 - a) / n.(b - a), n = (c1 - c0) x (c2 - c0), of the
/// edge (a, b) of `self` (ordered_edge) with the plane of `other` (c0, c1, c2), s clamped to
/// [0, 1] (the predicates put a and b strictly on opposite sides; rounding may not: stay on the
/// edge). T is double or the AutoDiff scalar: make_end's value is this with T = double to the
/// last bit, because both do the same operations in the same order (segment relies on it and
/// DCHECKs it). Hence the dot product written out: Eigen's own sums a double 3-vector's products
/// in another order than an AutoDiff one's (the points then differed in the last bit).
template <class T>
Eigen::Matrix<T, 3, 1> edge_plane_point(const Eigen::Matrix<T, 3, 1>& a, const Eigen::Matrix<T, 3, 1>& b,
                                        const Eigen::Matrix<T, 3, 1>& c0, const Eigen::Matrix<T, 3, 1>& c1,
                                        const Eigen::Matrix<T, 3, 1>& c2) {
  auto dot = [](const Eigen::Matrix<T, 3, 1>& u, const Eigen::Matrix<T, 3, 1>& v) -> T {
    return u[0] * v[0] + (u[1] * v[1] + u[2] * v[2]);
  };
  const Eigen::Matrix<T, 3, 1> n = (c1 - c0).cross(c2 - c0);
  T s = dot(n, c0 - a) / dot(n, b - a);
  if constexpr (std::is_same_v<T, double>) {
    if (!(s >= 0)) s = 0.0;
    if (!(s <= 1)) s = 1.0;
  } else {
    if (!(s.value() >= 0)) s = T(0.0, Eigen::Matrix<double, 15, 1>::Zero());
    if (!(s.value() <= 1)) s = T(1.0, Eigen::Matrix<double, 15, 1>::Zero());
  }
  return a + (b - a) * s;
}

/// The point of the end made by `rule` (make_end's, without its Jacobian).
Vec3 end_point(const EndRule& rule, const std::array<const Tri*, 2>& tri) {
  const Tri& self = *tri[size_t(rule.self)];
  if (rule.j < 0) return self.x[size_t(rule.i)];  // a shared vertex
  const Tri& other = *tri[size_t(1 - rule.self)];
  const auto [i, j] = ordered_edge(rule, self);
  return edge_plane_point<double>(self.x[size_t(i)], self.x[size_t(j)], other.x[0], other.x[1], other.x[2]);
}

/// The end made by `rule` with its Jacobian (see CrossingEnd); the point itself in `point`.
CrossingEnd make_end(const EndRule& rule, const std::array<const Tri*, 2>& tri, Vec3& point) {
  CrossingEnd end;
  const Tri& self = *tri[size_t(rule.self)];
  if (rule.j < 0) {  // a shared vertex
    end.vertices[0] = self.ref[size_t(rule.i)];
    end.jacobian.leftCols<3>().setIdentity();
    point = self.x[size_t(rule.i)];
    return end;
  }
  const Tri& other = *tri[size_t(1 - rule.self)];
  const auto [i, j] = ordered_edge(rule, self);
  const Vec3AD X = edge_plane_point<AD>(variable(self.x[size_t(i)], 0), variable(self.x[size_t(j)], 1),
                                        variable(other.x[0], 2), variable(other.x[1], 3), variable(other.x[2], 4));
  end.vertices = {self.ref[size_t(i)], self.ref[size_t(j)], other.ref[0], other.ref[1], other.ref[2]};
  for (int k = 0; k < 3; ++k) {
    point[k] = X[k].value();
    end.jacobian.row(k) = X[k].derivatives().transpose();
  }
  return end;
}

/// Which vertices of A and B the two share (by position: welded meshes share positions exactly
/// where they share vertices; two shapes may too), and how many.
struct Sharing {
  std::array<std::array<bool, 3>, 2> shared{};
  int count = 0;
};

Sharing sharing(const Tri& A, const Tri& B) {
  Sharing s;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (A.x[size_t(i)] == B.x[size_t(j)]) {
        s.shared[0][size_t(i)] = s.shared[1][size_t(j)] = true;
        ++s.count;
      }
  return s;
}

/// True iff two or more (i, j) have triangle f's vertex index i equal to g's index j: they share
/// an edge, or are one triangle twice (or a degenerate triangle's repeated index meets the other),
/// so sharing() would count >= 2 by positions too. Read from
/// the indices alone, before any position: in a closed mesh a quarter of the broad phase's pairs.
bool shares_an_edge(const TriangleMesh& mesh, int f, int g) {
  const auto& a = mesh.triangles[size_t(f)];
  const auto& b = mesh.triangles[size_t(g)];
  int n = 0;
  for (int i = 0; i < 3; ++i) n += (a[i] == b[0]) + (a[i] == b[1]) + (a[i] == b[2]);
  return n >= 2;
}

/// How a triangle meets the other's plane: strictly on both sides (Cross), with exactly one edge
/// in the plane and its third vertex strictly in front of it (EdgeInPlane: a crossing only if
/// the triangle across that edge lies strictly behind, pending_segment), or neither.
enum class Meets { None, Cross, EdgeInPlane };

struct Sides {
  std::array<std::array<int, 3>, 2> side{};  ///< per triangle and vertex: -1, 0 (in the plane), +1
  std::array<Meets, 2> meets{Meets::None, Meets::None};
};

/// The exact sides of every vertex of A and B against the other's plane (a shared vertex: 0).
/// Where A meets B's plane in neither way (Meets::None) the pair cannot cross (a crossing needs
/// both to meet, see narrow_phase and pending_segment), so B's sides are not computed: they stay
/// 0 and B's meets None.
Sides sides(const Tri& A, const Tri& B, const Sharing& sh) {
  Sides out;
  const std::array<const Tri*, 2> tri{&A, &B};
  for (int t = 0; t < 2 && (t == 0 || out.meets[0] != Meets::None); ++t) {
    const Tri& self = *tri[size_t(t)];
    const Tri& other = *tri[size_t(1 - t)];
    int plus = 0, minus = 0;
    for (int i = 0; i < 3; ++i) {
      const int s =
          sh.shared[size_t(t)][size_t(i)] ? 0 : orientation(other.x[0], other.x[1], other.x[2], self.x[size_t(i)]);
      out.side[size_t(t)][size_t(i)] = s;
      plus += s > 0;
      minus += s < 0;
    }
    if (plus > 0 && minus > 0)
      out.meets[size_t(t)] = Meets::Cross;
    else if (plus == 1 && minus == 0)
      out.meets[size_t(t)] = Meets::EdgeInPlane;
  }
  return out;
}

/// The segment of A and B given their sides (each triangle crossing the other's plane, or lying
/// on it with an edge: see Meets): the overlap of the two triangles' intervals on the line where
/// the planes meet, when it is more than a point. A vertex in the other plane is an end of its
/// triangle's interval; an edge whose ends are strictly on opposite sides gives the other end.
std::optional<CrossingSegment> segment(const Tri& A, const Tri& B, const Sides& sd) {
  const std::array<const Tri*, 2> tri{&A, &B};
  // ---- Each triangle's interval on the planes' common line (direction D = nA x nB).
  const Vec3 nA = (A.x[1] - A.x[0]).cross(A.x[2] - A.x[0]), nB = (B.x[1] - B.x[0]).cross(B.x[2] - B.x[0]);
  const Vec3 D = nA.cross(nB);
  if (!(D.squaredNorm() > 0) || !D.allFinite()) return std::nullopt;
  struct Candidate {
    EndRule rule;
    Vec3 point;
    double lambda;
  };
  std::array<std::array<Candidate, 2>, 2> ends;
  for (int t = 0; t < 2; ++t) {
    int k = 0;
    const auto& s = sd.side[size_t(t)];
    for (int i = 0; i < 3 && k < 2; ++i) {
      if (s[size_t(i)] == 0) ends[size_t(t)][size_t(k++)].rule = {t, i, -1};
      const int j = (i + 1) % 3;
      if (k < 2 && s[size_t(i)] * s[size_t(j)] < 0) ends[size_t(t)][size_t(k++)].rule = {t, i, j};
    }
    if (k != 2) return std::nullopt;  // cannot happen for Cross or EdgeInPlane (kept for safety)
    for (Candidate& c : ends[size_t(t)]) {
      c.point = end_point(c.rule, tri);
      c.lambda = D.dot(c.point);
    }
    if (ends[size_t(t)][1].lambda < ends[size_t(t)][0].lambda) std::swap(ends[size_t(t)][0], ends[size_t(t)][1]);
  }
  // ---- The overlap of the two intervals: more than a point.
  const Candidate& lo = ends[0][0].lambda >= ends[1][0].lambda ? ends[0][0] : ends[1][0];
  const Candidate& hi = ends[0][1].lambda <= ends[1][1].lambda ? ends[0][1] : ends[1][1];
  if (!(lo.lambda < hi.lambda) || lo.point == hi.point || !lo.point.allFinite() || !hi.point.allFinite())
    return std::nullopt;
  // ---- Only now the ends' Jacobians (AutoDiff): most candidate pairs of a bumpy surface that
  // cross each other's plane share a vertex and overlap only there.
  CrossingSegment seg;
  Vec3 p0, p1;
  seg.ends = {make_end(lo.rule, tri, p0), make_end(hi.rule, tri, p1)};
  QSIL_DCHECK_MSG(p0 == lo.point && p1 == hi.point, "intersection curve: an end's point differs from its Jacobian's");
  seg.p0 = lo.point;
  seg.p1 = hi.point;
  const std::array<Vec3, 2> n{nA.normalized(), nB.normalized()};
  for (int t = 0; t < 2; ++t) {
    const Tri& self = *tri[size_t(t)];
    seg.plane[size_t(t)] << n[size_t(t)], -n[size_t(t)].dot(self.x[0]);
  }
  return seg;
}

/// A pair whose crossing depends on a neighbouring triangle: triangle `which` (0: the pair's
/// first, 1: its second) lies on the other's plane with its edge (i, j), its third vertex in front.
struct Pending {
  TrianglePair pair;
  int which = 0, i = 0, j = 0;
};

/// The triangles of a mesh by undirected edge: (min vertex, max vertex, triangle), sorted.
std::vector<std::array<int, 3>> edge_table(const TriangleMesh& mesh) {
  std::vector<std::array<int, 3>> t;
  t.reserve(3 * mesh.triangles.size());
  for (int f = 0; f < mesh.num_triangles(); ++f)
    for (int k = 0; k < 3; ++k) {
      const int a = mesh.triangles[size_t(f)][k], b = mesh.triangles[size_t(f)][(k + 1) % 3];
      t.push_back({std::min(a, b), std::max(a, b), f});
    }
  std::sort(t.begin(), t.end());
  return t;
}

/// Triangle f of meshes[mesh]: its vertex positions (world frame) and references.
Tri triangle(std::span<const CurveMesh> meshes, int mesh, int f) {
  const CurveMesh& m = meshes[size_t(mesh)];
  Tri t;
  for (int k = 0; k < 3; ++k) {
    const int v = m.mesh->triangles[size_t(f)][k];
    t.x[size_t(k)] = m.mesh->positions[size_t(v)];
    t.ref[size_t(k)] = {m.shape, v};
  }
  return t;
}

/// Labels the segment of pair p with the pair's shapes and faces.
void finish(std::span<const CurveMesh> meshes, const TrianglePair& p, CrossingSegment& seg) {
  seg.shape = {meshes[size_t(p.mesh0)].shape, meshes[size_t(p.mesh1)].shape};
  seg.face = {p.triangle0, p.triangle1};
}

/// The order of pairs: by (mesh0, triangle0, mesh1, triangle1).
auto pair_key(const TrianglePair& p) { return std::tie(p.mesh0, p.triangle0, p.mesh1, p.triangle1); }

/// What the narrow phase found on one thread: the crossing pairs, the pairs that depend on a
/// neighbouring triangle (Pending), and how many pairs it saw.
struct NarrowResults {
  std::vector<std::pair<TrianglePair, CrossingSegment>> found;
  std::vector<Pending> pending;
  long long pairs = 0;
  std::vector<CandidatePairCache::Pair> kept;  ///< pairs for a CandidatePairCache being filled
  long long edge_sharing = 0;                  ///< pairs sharing an edge by index (not kept)
};

/// The narrow phase of candidate pair p, triangles A and B (see narrow_phase), pairs that share
/// an edge by index already set aside.
void narrow_phase_of(std::span<const CurveMesh> meshes, const TrianglePair& p, const Tri& A, const Tri& B,
                     NarrowResults& out) {
  const Sharing sh = sharing(A, B);
  if (sh.count >= 2) return;  // an edge (or the triangle) in common: no crossing
  const Sides sd = sides(A, B, sh);
  if (sd.meets[0] == Meets::Cross && sd.meets[1] == Meets::Cross) {
    std::optional<CrossingSegment> seg = segment(A, B, sd);
    if (!seg) return;
    finish(meshes, p, *seg);
    out.found.emplace_back(p, *seg);
  } else {
    for (int t = 0; t < 2; ++t)
      if (sd.meets[size_t(t)] == Meets::EdgeInPlane && sd.meets[size_t(1 - t)] == Meets::Cross) {
        const auto& sgn = sd.side[size_t(t)];
        const int k = sgn[0] > 0 ? 0 : (sgn[1] > 0 ? 1 : 2);  // the vertex in front; the edge is the other two
        out.pending.push_back({p, t, (k + 1) % 3, (k + 2) % 3});
      }
  }
}

/// The narrow phase of one candidate pair p: its segment into out.found when both triangles
/// cross the other's plane, or into out.pending when one lies on the other's plane with an edge.
void narrow_phase(std::span<const CurveMesh> meshes, const TrianglePair& p, NarrowResults& out) {
  ++out.pairs;
  if (p.mesh0 == p.mesh1 && shares_an_edge(*meshes[size_t(p.mesh0)].mesh, p.triangle0, p.triangle1)) return;
  narrow_phase_of(meshes, p, triangle(meshes, p.mesh0, p.triangle0), triangle(meshes, p.mesh1, p.triangle1), out);
}

/// The segment of a pending pair, if it crosses: a triangle with an edge in the other's plane
/// crosses it along that edge when the triangle across the edge lies strictly behind the plane
/// (a ring of vertices exactly in the other surface); with it in front or in the plane, the
/// surfaces only touch there. `tables`: each mesh's edge_table, built on first use.
std::optional<CrossingSegment> pending_segment(std::span<const CurveMesh> meshes, const Pending& pd,
                                               std::vector<std::vector<std::array<int, 3>>>& tables) {
  const TrianglePair& p = pd.pair;
  const int mesh = pd.which == 0 ? p.mesh0 : p.mesh1, face = pd.which == 0 ? p.triangle0 : p.triangle1;
  const TriangleMesh& m = *meshes[size_t(mesh)].mesh;
  if (tables[size_t(mesh)].empty()) tables[size_t(mesh)] = edge_table(m);
  const auto& table = tables[size_t(mesh)];
  const int a = m.triangles[size_t(face)][pd.i], c = m.triangles[size_t(face)][pd.j];
  const std::array<int, 3> edge{std::min(a, c), std::max(a, c), -1};
  auto it = std::lower_bound(table.begin(), table.end(), edge);
  std::vector<int> across;
  for (; it != table.end() && (*it)[0] == edge[0] && (*it)[1] == edge[1]; ++it)
    if ((*it)[2] != face) across.push_back((*it)[2]);
  if (across.size() != 1) return std::nullopt;  // a boundary or non-manifold edge
  const Tri A = triangle(meshes, p.mesh0, p.triangle0), B = triangle(meshes, p.mesh1, p.triangle1);
  const Tri& other = pd.which == 0 ? B : A;
  const Tri N = triangle(meshes, mesh, across[0]);
  int third = 0;
  for (int k = 0; k < 3; ++k)
    if (m.triangles[size_t(across[0])][k] != a && m.triangles[size_t(across[0])][k] != c) third = k;
  if (orientation(other.x[0], other.x[1], other.x[2], N.x[size_t(third)]) >= 0) return std::nullopt;
  std::optional<CrossingSegment> seg = segment(A, B, sides(A, B, sharing(A, B)));
  if (seg) finish(meshes, p, *seg);
  return seg;
}

/// True iff the boxes of p's triangles overlap (closed, in double): the broad phase's exact test.
bool boxes_overlap(std::span<const CurveMesh> meshes, const TrianglePair& p) {
  const Box3 a = meshes[size_t(p.mesh0)].mesh->triangle_bounds(p.triangle0);
  return a.within(meshes[size_t(p.mesh1)].mesh->triangle_bounds(p.triangle1));
}

/// boxes_overlap of two triangles already read: the same boxes (a coordinate's min and max do not
/// depend on the order), hence the same answer.
bool boxes_overlap(const Tri& A, const Tri& B) {
  Box3 a, b;
  for (int k = 0; k < 3; ++k) {
    a.expand(A.x[size_t(k)]);
    b.expand(B.x[size_t(k)]);
  }
  return a.within(b);
}

/// True iff triangles f and g of one mesh share a vertex index. Their boxes then overlap, for both
/// hold that vertex's position. In a closed mesh that is more than half of a cache's pairs
/// (CandidatePairCache): a triangle among valence-6 vertices has 9 neighbours by a vertex alone.
bool shares_a_vertex(const TriangleMesh& mesh, int f, int g) {
  const auto& a = mesh.triangles[size_t(f)];
  const auto& b = mesh.triangles[size_t(g)];
  for (int i = 0; i < 3; ++i)
    if (a[i] == b[0] || a[i] == b[1] || a[i] == b[2]) return true;
  return false;
}

/// FNV-1a over every mesh's triangle count and vertex indices.
std::uint64_t triangles_hash(std::span<const CurveMesh> meshes) {
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&](std::int64_t x) {
    for (int i = 0; i < 8; ++i, x >>= 8) {
      h ^= std::uint64_t(x & 0xff);
      h *= 1099511628211ull;
    }
  };
  for (const CurveMesh& m : meshes) {
    mix(m.mesh->num_triangles());
    for (const auto& t : m.mesh->triangles)
      for (int k = 0; k < 3; ++k) mix(t[k]);
  }
  return h;
}

/// What a search finds of its cache (CandidatePairCache): it serves `meshes` (the same counts and
/// triangles, finite coordinates, and no vertex moved more than gap / 2 on any axis since it was
/// filled), the vertices moved too far, or it holds nothing for them.
enum class CacheCheck { Serves, MovedTooFar, Unusable };

CacheCheck check_cache(const CandidatePairCache& cache, std::span<const CurveMesh> meshes) {
  if (!cache.valid || cache.positions.size() != meshes.size()) return CacheCheck::Unusable;
  for (size_t i = 0; i < meshes.size(); ++i)
    if (cache.positions[i].size() != meshes[i].mesh->positions.size() ||
        cache.triangle_counts[i] != meshes[i].mesh->num_triangles())
      return CacheCheck::Unusable;
  if (triangles_hash(meshes) != cache.triangles_hash) return CacheCheck::Unusable;
  double d = 0.0;
  for (size_t i = 0; i < meshes.size(); ++i) {
    const std::vector<Vec3>& now = meshes[i].mesh->positions;
    for (size_t v = 0; v < now.size(); ++v) {
      // A coordinate that is not finite (or a move that overflows) makes the cache unusable; tested
      // per coordinate, for maxCoeff would pass over a NaN in y or z.
      const Vec3 delta = now[v] - cache.positions[i][v];
      if (!delta.allFinite()) return CacheCheck::Unusable;
      d = std::max(d, delta.cwiseAbs().maxCoeff());
    }
  }
  // fl(x - y) = (x - y)(1 + e), |e| <= 2^-53: the true move is at most d (1 + 2^-52), and the
  // product below rounds by 2^-53 more.
  return 2.0 * d * (1.0 + 0x1p-50) <= cache.gap ? CacheCheck::Serves : CacheCheck::MovedTooFar;
}

/// How a search with a cache runs: from the cache, filling it, or without it.
enum class CacheUse { Reuse, Fill, Plain };

/// The cache's policy (CandidatePairCache::gap_edges, served, rest): at gaps up to
/// kCandidatePairMaxGap a fill costs 1.1-1.5 searches without a cache and a search from it
/// 0.3-0.4 (measured in docs/experiments/2026-11-26-candidate-pair-cache.md), so a fill pays
/// where it serves at least one search. The gap doubles (up to kCandidatePairMaxGap) when the
/// vertices moved out of it before two searches, and halves (down to kCandidatePairMinGap)
/// after more than eight; where even the largest gap served none, the next kCandidatePairRest
/// searches run without the cache (and it frees its arrays meanwhile).
CacheUse plan(CandidatePairCache& cache, CacheCheck check) {
  if (check == CacheCheck::Serves) {
    ++cache.served;
    return CacheUse::Reuse;
  }
  if (cache.rest > 0) {
    --cache.rest;
    return CacheUse::Plain;
  }
  if (check == CacheCheck::MovedTooFar) {
    if (cache.served < 2) {
      if (cache.served == 0 && cache.gap_edges >= kCandidatePairMaxGap) {
        CandidatePairCache resting;
        resting.gap_edges = cache.gap_edges;
        resting.rest = kCandidatePairRest - 1;
        cache = std::move(resting);
        return CacheUse::Plain;
      }
      cache.gap_edges = std::min(2.0 * cache.gap_edges, kCandidatePairMaxGap);
    } else if (cache.served > 8) {
      cache.gap_edges = std::max(0.5 * cache.gap_edges, kCandidatePairMinGap);
    }
  }
  return CacheUse::Fill;
}

/// The meshes' mean edge length (each triangle's three, over every triangle with finite
/// vertices; 0 if none).
double mean_edge_length(std::span<const CurveMesh> meshes) {
  double sum = 0.0;
  long long n = 0;
  for (const CurveMesh& m : meshes)
    for (const auto& t : m.mesh->triangles)
      for (int k = 0; k < 3; ++k) {
        const double l = (m.mesh->positions[size_t(t[k])] - m.mesh->positions[size_t(t[(k + 1) % 3])]).norm();
        if (std::isfinite(l)) {
          sum += l;
          ++n;
        }
      }
  return n ? sum / double(n) : 0.0;
}

bool all_finite(std::span<const CurveMesh> meshes) {
  for (const CurveMesh& m : meshes)
    for (const Vec3& x : m.mesh->positions)
      if (!x.allFinite()) return false;
  return true;
}

}  // namespace

SceneVelocities::Block crossing_end_velocity(const CrossingEnd& end, const SceneVelocities& velocities) {
  SceneVelocities::Block v = SceneVelocities::Block::Zero();
  for (int i = 0; i < 5; ++i) {
    const VertexRef& r = end.vertices[size_t(i)];
    if (r.shape < 0 || r.shape >= int(velocities.position.size())) continue;
    const auto& V = velocities.position[size_t(r.shape)];
    if (r.vertex < 0 || r.vertex >= int(V.size())) continue;
    v += end.jacobian.middleCols<3>(3 * i) * V[size_t(r.vertex)];
  }
  return v;
}

size_t CandidatePairCache::memory_bytes() const {
  size_t bytes =
      pairs.capacity() * sizeof(Pair) + (triangle_counts.capacity() + first_triangle.capacity()) * sizeof(int);
  for (const auto& p : positions) bytes += p.capacity() * sizeof(Vec3);
  return bytes;
}

std::vector<CrossingSegment> find_intersection_curves(std::span<const CurveMesh> meshes, IntersectionCurveStats* stats,
                                                      CandidatePairCache* cache) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<const TriangleMesh*> ptrs;
  for (const CurveMesh& m : meshes) ptrs.push_back(m.mesh);
  tbb::enumerable_thread_specific<NarrowResults> local;
  double build_seconds = 0;
  const CacheUse use = cache ? plan(*cache, check_cache(*cache, meshes)) : CacheUse::Plain;
  const bool from_cache = use == CacheUse::Reuse;
  if (from_cache) {
    // ---- The cached pairs, with the broad phase's exact box test on the moved meshes.
    const std::vector<CandidatePairCache::Pair>& pairs = cache->pairs;
    const std::vector<int>& first = cache->first_triangle;
    auto unpack = [&](int t, int& mesh, int& f) {  // the mesh whose range holds t
      mesh = int(std::upper_bound(first.begin(), first.end(), t) - first.begin()) - 1;
      f = t - first[size_t(mesh)];
    };
    tbb::parallel_for(tbb::blocked_range<size_t>(0, pairs.size(), 1024), [&](const tbb::blocked_range<size_t>& r) {
      NarrowResults& out = local.local();
      for (size_t i = r.begin(); i < r.end(); ++i) {
        TrianglePair p;
        unpack(pairs[i].a, p.mesh0, p.triangle0);
        unpack(pairs[i].b, p.mesh1, p.triangle1);
        // The broad phase's exact box test where the pair shares no vertex, on the triangles the
        // narrow phase reads; no pair here shares an edge by index (the fill set those aside).
        const Tri A = triangle(meshes, p.mesh0, p.triangle0), B = triangle(meshes, p.mesh1, p.triangle1);
        if (!(p.mesh0 == p.mesh1 && shares_a_vertex(*meshes[size_t(p.mesh0)].mesh, p.triangle0, p.triangle1)) &&
            !boxes_overlap(A, B))
          continue;
        ++out.pairs;
        narrow_phase_of(meshes, p, A, B, out);
      }
    });
    local.local().pairs += cache->edge_sharing_pairs;  // they overlap wherever coordinates are finite
  } else if (use == CacheUse::Fill) {
    // ---- The broad phase with the cache's gap: every pair is kept, those whose boxes overlap
    // go to the narrow phase (Embree's threads, per thread).
    CandidatePairCache fresh;
    fresh.gap_edges = cache->gap_edges;
    *cache = std::move(fresh);
    const double gap = cache->gap_edges * mean_edge_length(meshes);
    std::vector<long long> first(1, 0);
    for (const CurveMesh& m : meshes) first.push_back(first.back() + m.mesh->num_triangles());
    const bool indexable = first.back() <= std::numeric_limits<int>::max();  // else no cache is kept
    for_each_overlapping_triangle_pair(
        ptrs,
        [&](const TrianglePair& p) {
          NarrowResults& out = local.local();
          const bool overlap = boxes_overlap(meshes, p);
          if (p.mesh0 == p.mesh1 && shares_an_edge(*meshes[size_t(p.mesh0)].mesh, p.triangle0, p.triangle1))
            out.edge_sharing += overlap;
          else if (indexable)
            out.kept.push_back({int(first[size_t(p.mesh0)] + p.triangle0), int(first[size_t(p.mesh1)] + p.triangle1)});
          if (overlap) narrow_phase(meshes, p, out);
        },
        &build_seconds, gap);
    if (indexable && all_finite(meshes)) {
      for (NarrowResults& l : local) {
        cache->pairs.insert(cache->pairs.end(), l.kept.begin(), l.kept.end());
        cache->edge_sharing_pairs += l.edge_sharing;
        l.kept = {};
      }
      for (const CurveMesh& m : meshes) {
        cache->positions.push_back(m.mesh->positions);
        cache->triangle_counts.push_back(m.mesh->num_triangles());
      }
      for (long long f : first) cache->first_triangle.push_back(int(f));
      cache->triangles_hash = triangles_hash(meshes);
      cache->gap = gap;
      cache->valid = true;
    }
  } else {
    // ---- The narrow phase inside the broad phase's callback (Embree's threads), per thread.
    for_each_overlapping_triangle_pair(
        ptrs, [&](const TrianglePair& p) { narrow_phase(meshes, p, local.local()); }, &build_seconds);
  }
  std::vector<std::pair<TrianglePair, CrossingSegment>> found;
  std::vector<Pending> pending;
  long long candidate_pairs = 0;
  for (NarrowResults& l : local) {
    found.insert(found.end(), l.found.begin(), l.found.end());
    pending.insert(pending.end(), l.pending.begin(), l.pending.end());
    candidate_pairs += l.pairs;
  }
  std::sort(pending.begin(), pending.end(), [&](const Pending& a, const Pending& b) {
    return std::tuple_cat(pair_key(a.pair), std::tie(a.which)) < std::tuple_cat(pair_key(b.pair), std::tie(b.which));
  });
  // ---- The pairs with a triangle's edge in the other's plane (see pending_segment).
  std::vector<std::vector<std::array<int, 3>>> tables(meshes.size());
  for (const Pending& pd : pending) {
    std::optional<CrossingSegment> seg = pending_segment(meshes, pd, tables);
    if (!seg) continue;
    found.emplace_back(pd.pair, *seg);
  }
  // ---- A deterministic order, whatever the threads did: by the pair.
  std::sort(found.begin(), found.end(),
            [&](const auto& a, const auto& b) { return pair_key(a.first) < pair_key(b.first); });
  std::vector<CrossingSegment> out;
  out.reserve(found.size());
  for (auto& f : found) out.push_back(f.second);
  if (stats) {
    stats->candidate_pairs = candidate_pairs;
    stats->crossing_pairs = (long long)out.size();
    stats->build_seconds = build_seconds;
    stats->from_cache = from_cache;
    stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  return out;
}

}  // namespace qsil::edgetree
