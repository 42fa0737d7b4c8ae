/// @file mesh_edges.cpp
/// Edge extraction and classification (docs/architecture.md §5 "Edges").

#include "qsil/edgetree/mesh_edges.h"

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>

namespace qsil::edgetree {

Vec4 face_plane(const TriangleMesh& mesh, int f) {
  const Vec3 c = mesh.face_cross(f);
  const double len = c.norm();
  if (!(len > 0.0) || !std::isfinite(len)) return Vec4::Zero();
  const Vec3 n = c / len;
  // Offset from the centroid: the rounding error is then symmetric over the three vertices.
  const auto& t = mesh.triangles[f];
  const Vec3 x0 = (mesh.positions[t[0]] + mesh.positions[t[1]] + mesh.positions[t[2]]) / 3.0;
  return Vec4(n.x(), n.y(), n.z(), -n.dot(x0));
}

EdgeClass classify_interior_edge(const TriangleMesh& mesh, MeshEdge& e) {
  // Bend angle between the outward normals (atan2 is accurate near 0 and pi).
  const Vec3 n0 = e.q0.head<3>(), n1 = e.q1.head<3>();
  e.angle = std::atan2(n0.cross(n1).norm(), n0.dot(n1));
  if (e.angle < kFlatAngle) return EdgeClass::Flat;
  // Concave iff the other face's opposite vertex d is on the positive side of f0's plane
  // (meshes README). Evaluated relative to a vertex of f0 with the unnormalised normal.
  const int d = opposite_vertex_index(mesh, e, e.f1);
  const Vec3 a = mesh.positions[size_t(mesh.triangles[size_t(e.f0)][0])];
  const double side = mesh.face_cross(e.f0).dot(mesh.positions[size_t(d)] - a);
  return side > 0.0 ? EdgeClass::Concave : EdgeClass::Convex;
}

namespace {
// One directed half-edge: key (min vertex, max vertex), its face, and whether it runs min -> max.
struct HalfEdge {
  int a, b, face;
  bool forward;
  bool operator<(const HalfEdge& o) const { return a != o.a ? a < o.a : (b != o.b ? b < o.b : face < o.face); }
};
}  // namespace

MeshEdgeSet build_mesh_edges(const TriangleMesh& mesh, int shape, const EdgeOptions& options) {
  MeshEdgeSet out;
  const int T = mesh.num_triangles();
  out.face_planes.resize(T);
  for (int f = 0; f < T; ++f) out.face_planes[f] = face_plane(mesh, f);

  std::vector<HalfEdge> half;
  half.reserve(size_t(3) * T);
  for (int f = 0; f < T; ++f) {
    const auto& t = mesh.triangles[f];
    for (int k = 0; k < 3; ++k) {
      const int u = t[k], v = t[(k + 1) % 3];
      half.push_back({std::min(u, v), std::max(u, v), f, u < v});
    }
  }
  tbb::parallel_sort(half.begin(), half.end());

  for (size_t i = 0; i < half.size();) {
    size_t j = i;
    while (j < half.size() && half[j].a == half[i].a && half[j].b == half[i].b) ++j;
    const int nf = int(j - i);
    MeshEdge e;
    e.v0 = half[i].a;
    e.v1 = half[i].b;
    e.shape = shape;
    e.f0 = half[i].face;
    e.q0 = out.face_planes[e.f0];
    e.length = (mesh.positions[e.v1] - mesh.positions[e.v0]).norm();
    if (nf >= 2) {
      e.f1 = half[i + 1].face;
      e.q1 = out.face_planes[e.f1];
    }
    if (nf == 1) {
      e.cls = EdgeClass::Boundary;
    } else if (nf > 2) {
      e.cls = EdgeClass::NonManifold;
    } else if (half[i].forward == half[i + 1].forward) {
      e.cls = EdgeClass::Inconsistent;
    } else {
      e.cls = classify_interior_edge(mesh, e);
    }
    out.counts[static_cast<int>(e.cls)]++;
    const int idx = int(out.edges.size());
    switch (e.cls) {
      case EdgeClass::Convex: out.kept.push_back(idx); break;
      case EdgeClass::Concave:
        if (options.keep_concave) out.kept.push_back(idx);
        break;
      case EdgeClass::Flat: break;
      default: out.always.push_back(idx); break;
    }
    out.edges.push_back(e);
    i = j;
  }
  return out;
}

}  // namespace qsil::edgetree
