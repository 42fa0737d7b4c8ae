/// @file mesh_edges.cpp
/// Edge extraction and classification (docs/architecture.md §5 "Edges").

#include "qsil/edgetree/mesh_edges.h"

#include <tbb/parallel_for.h>
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
  tbb::parallel_for(0, T, [&](int f) { out.face_planes[size_t(f)] = face_plane(mesh, f); });

  std::vector<HalfEdge> half(size_t(3) * T);
  tbb::parallel_for(0, T, [&](int f) {
    const auto& t = mesh.triangles[size_t(f)];
    for (int k = 0; k < 3; ++k) {
      const int u = t[k], v = t[(k + 1) % 3];
      half[size_t(3) * f + k] = {std::min(u, v), std::max(u, v), f, u < v};
    }
  });
  tbb::parallel_sort(half.begin(), half.end());

  // An edge per run of half-edges with one key: the runs first, then the edges from them in
  // parallel (each from its run alone), so that the array is written once at its final size.
  std::vector<size_t> run;  // first half-edge of every edge, then half.size()
  run.reserve(half.size() / 2 + 1);
  for (size_t i = 0; i < half.size(); ++i)
    if (i == 0 || half[i].a != half[i - 1].a || half[i].b != half[i - 1].b) run.push_back(i);
  run.push_back(half.size());
  out.edges.resize(run.size() - 1);
  tbb::parallel_for(size_t(0), out.edges.size(), [&](size_t k) {
    const size_t i = run[k];
    const int nf = int(run[k + 1] - i);
    MeshEdge& e = out.edges[k];
    e.v0 = half[i].a;
    e.v1 = half[i].b;
    e.shape = shape;
    e.f0 = half[i].face;
    e.q0 = out.face_planes[size_t(e.f0)];
    e.length = (mesh.positions[size_t(e.v1)] - mesh.positions[size_t(e.v0)]).norm();
    if (nf >= 2) {
      e.f1 = half[i + 1].face;
      e.q1 = out.face_planes[size_t(e.f1)];
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
  });
  for (size_t k = 0; k < out.edges.size(); ++k) {
    const EdgeClass cls = out.edges[k].cls;
    out.counts[static_cast<int>(cls)]++;
    switch (cls) {
      case EdgeClass::Convex: out.kept.push_back(int(k)); break;
      case EdgeClass::Concave:
        if (options.keep_concave) out.kept.push_back(int(k));
        break;
      case EdgeClass::Flat: break;
      default: out.always.push_back(int(k)); break;
    }
  }
  return out;
}

}  // namespace qsil::edgetree
