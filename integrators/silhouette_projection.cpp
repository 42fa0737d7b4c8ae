/// @file silhouette_projection.cpp
/// See silhouette_projection.h.

#include "silhouette_projection.h"

#include "qsil/sampling.h"

#include <algorithm>
#include <cmath>

namespace qsil {

namespace {

/// |cos| of the angle under which x sees triangle f of `mesh` (its geometric normal against the
/// direction to its centroid); 1 for a degenerate triangle (the walk takes it only when no other
/// neighbour is left).
double facing(const TriangleMesh& mesh, int f, const Vec3& x) {
  const Eigen::Vector3i& tri = mesh.triangles[size_t(f)];
  const Vec3 c =
      (mesh.positions[size_t(tri[0])] + mesh.positions[size_t(tri[1])] + mesh.positions[size_t(tri[2])]) / 3.0;
  const Vec3 n = mesh.face_cross(f);
  const double nn = n.norm(), d = (x - c).norm();
  if (!(nn > 0 && d > 0)) return 1.0;
  return std::abs(n.dot(x - c)) / (nn * d);
}

/// Whether the projection stops at edge e seen from x: a silhouette (boundary edges included) or a
/// crease of a flat-shaded shape. A smooth crease that is no silhouette (every convex edge of a
/// two-sided smooth shape is one) bounds jumps only in slivers (design-notes "Crease samples"):
/// the walk goes on past it.
bool projection_target(const edgetree::Edge& e, const Vec3& x) {
  return !e.retired && (edgetree::edge_is_silhouette(e, x) || (e.crease && !e.smooth_crease));
}

/// The edges of triangle f of shape s where the projection stops seen from x (projection_target):
/// one of them and t on it drawn uniformly, as the point u of boundary_segment; none when there is
/// none or the direction is not the edge's.
std::optional<Vec3> segment_on_triangle(const ProjectiveEdges& edges, const TriangleEdges& tri, int s, int f,
                                        const Vec3& x, Sampler& sampler) {
  std::array<int, 3> found{};
  int k = 0;
  for (int i : tri.at(s, f))
    if (i >= 0 && projection_target(*edges.edges[size_t(i)], x)) found[size_t(k++)] = i;
  if (k == 0) return std::nullopt;
  const int i = found[size_t(std::min(k - 1, int(sampler.next() * k)))];
  const edgetree::Edge& e = *edges.edges[size_t(i)];
  const double t = std::min(sampler.next(), std::nextafter(1.0, 0.0));
  const Vec3 y = e.p0 + t * (e.p1 - e.p0);
  const Vec3 w = (y - x).normalized();
  if (!w.allFinite()) return std::nullopt;
  return invert_boundary_segment(edges, size_t(i), t, w);
}

/// One Newton step from a random point of triangle f of shape s toward n_s . (x - p) = 0 (the
/// header), and the triangle of the same shape below the point it reaches; -1 for none.
int newton_jump(const PathContext& ctx, int s, int f, const Vec3& x, Sampler& sampler, PathStats& stats) {
  const TriangleMesh& mesh = ctx.scene->shapes[size_t(s)].mesh;
  if (mesh.normals.empty()) return -1;  // face normals: no smooth normal field to follow
  const Eigen::Vector3i& tri = mesh.triangles[size_t(f)];
  const Vec3 &p0 = mesh.positions[size_t(tri[0])], &p1 = mesh.positions[size_t(tri[1])],
             &p2 = mesh.positions[size_t(tri[2])];
  const Vec3 &n0 = mesh.normals[size_t(tri[0])], &n1 = mesh.normals[size_t(tri[1])], &n2 = mesh.normals[size_t(tri[2])];
  const Vec3 b = square_to_uniform_triangle(sampler.next2());
  const Vec3 p = b[2] * p0 + b[0] * p1 + b[1] * p2;
  const Vec3 n = b[2] * n0 + b[0] * n1 + b[1] * n2;
  const Vec3 dp_du = p1 - p0, dp_dv = p2 - p0, dn_du = n1 - n0, dn_dv = n2 - n0;
  const Vec3 h = (x - p).normalized();
  const double a = h.dot(dn_du), bb = h.dot(dn_dv), c = h.dot(n);
  const double ab = a * a + bb * bb;
  if (!(ab > 0) || !h.allFinite()) return -1;
  // The least step (du, dv) with h . (n + du dn_du + dv dn_dv) = 0.
  const double du = -a * c / ab, dv = -bb * c / ab;
  const Vec3 q = p + du * dp_du + dv * dp_dv;
  const Vec3 nq = (n + du * dn_du + dv * dn_dv).normalized();
  const double step = (q - p).norm();
  if (!q.allFinite() || !nq.allFinite() || !(step > 0)) return -1;
  // From just above the tangent plane's point, down its normal: the offset is relative to the
  // step, so the ray starts off the surface at any scene scale.
  ++stats.rays;
  const Hit below = ctx.tracer->intersect(q + nq * (1e-3 * step), -nq);
  return below.valid() && below.shape == s ? below.triangle : -1;
}

}  // namespace

TriangleEdges triangle_edges(const Scene& scene, const ProjectiveEdges& edges) {
  TriangleEdges out;
  out.of.resize(scene.shapes.size());
  for (size_t s = 0; s < scene.shapes.size(); ++s)
    out.of[s].assign(size_t(scene.shapes[s].mesh.num_triangles()), std::array<int, 3>{-1, -1, -1});
  for (size_t i = 0; i < edges.edges.size(); ++i) {
    const edgetree::Edge& e = *edges.edges[i];
    if (e.crossing || e.shape < 0 || e.shape >= int(out.of.size())) continue;
    for (int f : {e.f0, e.f1}) {
      if (f < 0 || f >= int(out.of[size_t(e.shape)].size())) continue;
      std::array<int, 3>& slots = out.of[size_t(e.shape)][size_t(f)];
      for (int& slot : slots)
        if (slot < 0 || slot == int(i)) {
          slot = int(i);
          break;
        }
    }
  }
  return out;
}

std::optional<Vec3> project_seed(const PathContext& ctx, const ProjectiveEdges& edges, const TriangleEdges& tri,
                                 const Vec3& x, const Hit& hit, Sampler& sampler, PathStats& stats) {
  if (!hit.valid()) return std::nullopt;
  const int s = hit.shape;
  const TriangleMesh& mesh = ctx.scene->shapes[size_t(s)].mesh;
  int f = hit.triangle, previous = -1;
  // ---- The walk: the hit's triangle, then across the edge toward the most nearly edge-on face
  // (not back to the triangle it came from).
  for (int step = 0; step <= kProjectionMaxWalk; ++step) {
    if (const std::optional<Vec3> u = segment_on_triangle(edges, tri, s, f, x, sampler)) return u;
    if (step == kProjectionMaxWalk) break;
    int next = -1;
    double best = kInf;
    for (int i : tri.at(s, f)) {
      if (i < 0) continue;
      const edgetree::Edge& e = *edges.edges[size_t(i)];
      const int g = e.f0 == f ? e.f1 : e.f0;
      if (g < 0 || g == f || g == previous) continue;
      const double c = facing(mesh, g, x);
      if (c < best) {
        best = c;
        next = g;
      }
    }
    if (next < 0) break;
    previous = f;
    f = next;
  }
  // ---- One Newton jump from the last triangle.
  const int g = newton_jump(ctx, s, f, x, sampler, stats);
  if (g < 0) return std::nullopt;
  return segment_on_triangle(edges, tri, s, g, x, sampler);
}

}  // namespace qsil
