#pragma once
/// @file vertex_normals.h
/// Area-weighted vertex normals over any scalar type (double, or a dual number so that the
/// normals' derivatives with respect to vertex motion come out in forward mode).

#include "qsil/dual.h"
#include "qsil/scene.h"

#include <vector>

namespace qsil {

/// Unit normal per vertex: the normalised sum of the (area-weighted) cross products of the
/// triangles around it; a vertex with no area gets +z. pos has mesh.num_vertices() entries.
template <class T>
std::vector<Vec3T<T>> vertex_normals_t(const TriangleMesh& mesh, const std::vector<Vec3T<T>>& pos) {
  std::vector<Vec3T<T>> n(pos.size(), Vec3T<T>(T(0.0), T(0.0), T(0.0)));
  for (const auto& t : mesh.triangles) {
    const Vec3T<T> c = (pos[t[1]] - pos[t[0]]).cross(pos[t[2]] - pos[t[0]]);
    for (int k = 0; k < 3; ++k) n[t[k]] += c;
  }
  for (auto& v : n) {
    using std::sqrt;
    const T len = sqrt(v.squaredNorm());
    if (value(len) > 0)
      v /= len;
    else
      v = Vec3T<T>(T(0.0), T(0.0), T(1.0));
  }
  return n;
}

/// Reverse mode of vertex_normals_t<double> (issue 17; qsil/integrators/reverse.h): given the
/// adjoint d_normal[i] = dL/dN_i of every unit vertex normal (mesh.num_vertices() entries; zero
/// for untouched vertices), adds dL/dx_j = sum_i (dN_i/dx_j)^T d_normal[i] to d_position[j] for
/// every vertex position x_j. Per vertex, N = s/|s| with s = sum of the cross products
/// c = (x1 - x0) x (x2 - x0) of its triangles, so dL/ds = (I - N N^T) d_normal / |s|; per
/// triangle, dL/dc is the sum of its vertices' dL/ds, and d(a.c) = dx1.(e2 x a) + dx2.(a x e1)
/// - dx0.(e2 x a + a x e1). A vertex with no area (constant +z normal) passes nothing on.
inline void vertex_normals_adjoint(const TriangleMesh& mesh, const std::vector<Vec3>& d_normal,
                                   std::vector<Vec3>& d_position) {
  const auto& P = mesh.positions;
  std::vector<Vec3> s(P.size(), Vec3::Zero());
  for (const auto& t : mesh.triangles) {
    const Vec3 c = (P[t[1]] - P[t[0]]).cross(P[t[2]] - P[t[0]]);
    for (int k = 0; k < 3; ++k) s[t[k]] += c;
  }
  std::vector<Vec3> d_s(P.size(), Vec3::Zero());
  for (size_t i = 0; i < P.size(); ++i) {
    const double len = s[i].norm();
    if (!(len > 0) || d_normal[i].isZero(0.0)) continue;
    const Vec3 n = s[i] / len;
    d_s[i] = (d_normal[i] - n * n.dot(d_normal[i])) / len;
  }
  for (const auto& t : mesh.triangles) {
    const Vec3 a = d_s[t[0]] + d_s[t[1]] + d_s[t[2]];
    if (a.isZero(0.0)) continue;
    const Vec3 e1 = P[t[1]] - P[t[0]], e2 = P[t[2]] - P[t[0]];
    const Vec3 g1 = e2.cross(a), g2 = a.cross(e1);
    d_position[t[1]] += g1;
    d_position[t[2]] += g2;
    d_position[t[0]] -= g1 + g2;
  }
}

}  // namespace qsil
