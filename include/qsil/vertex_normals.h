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

}  // namespace qsil
