#pragma once
// The soundness set of the edge forest (points where a false reject would show), shared by the rejection-test tests of
// every method (tests/edgetree/forest_soundness_test.cpp, tests/baselines/): a subdivided cube and shading points
// uniform around a mesh, near its surface and on its triangle planes.
#include "qsil/scene.h"

#include <cmath>
#include <random>
#include <vector>

namespace qsil::test {

/// A cube [-1,1]^3, each face an n x n grid of quads, welded.
inline TriangleMesh make_cube(int n) {
  TriangleMesh m;
  auto face = [&](const Vec3& o, const Vec3& u, const Vec3& v) {  // u x v is outward
    const int base = m.num_vertices();
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) m.positions.push_back(o + (2.0 * i / n) * u + (2.0 * j / n) * v);
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int a = base + j * (n + 1) + i, b = a + 1, c = a + n + 2, d = a + n + 1;
        m.triangles.push_back(Eigen::Vector3i(a, b, c));
        m.triangles.push_back(Eigen::Vector3i(a, c, d));
      }
  };
  face(Vec3(-1, -1, 1), Vec3(1, 0, 0), Vec3(0, 1, 0));
  face(Vec3(-1, 1, -1), Vec3(1, 0, 0), Vec3(0, -1, 0));
  face(Vec3(1, -1, -1), Vec3(0, 1, 0), Vec3(0, 0, 1));
  face(Vec3(-1, 1, -1), Vec3(0, -1, 0), Vec3(0, 0, 1));
  face(Vec3(1, 1, -1), Vec3(-1, 0, 0), Vec3(0, 0, 1));
  face(Vec3(-1, -1, -1), Vec3(1, 0, 0), Vec3(0, 0, 1));
  std::vector<int> remap(m.positions.size());
  std::vector<Vec3> uniq;
  for (size_t i = 0; i < m.positions.size(); ++i) {
    int found = -1;
    for (size_t k = 0; k < uniq.size() && found < 0; ++k)
      if (uniq[k] == m.positions[i]) found = int(k);
    if (found < 0) {
      found = int(uniq.size());
      uniq.push_back(m.positions[i]);
    }
    remap[i] = found;
  }
  for (auto& t : m.triangles)
    for (int k = 0; k < 3; ++k) t[k] = remap[size_t(t[k])];
  m.positions = uniq;
  return m;
}

/// 40% uniform in a box 3x the mesh's size, 30% near the surface (normal offsets 1e-1 .. 1e-12
/// of the diagonal, both sides), 30% on triangle planes (barycentrics in [-3, 3]).
inline std::vector<Vec3> shading_points(const TriangleMesh& m, int count, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const Box3 b = m.bounds();
  const Vec3 c = b.center(), e = b.extent();
  const double diag = b.diagonal();
  std::vector<Vec3> pts;
  for (int i = 0; i < count; ++i) {
    const double kind = u01(rng);
    if (kind < 0.4) {
      pts.push_back(c + 1.5 * Vec3((2 * u01(rng) - 1) * e.x(), (2 * u01(rng) - 1) * e.y(), (2 * u01(rng) - 1) * e.z()));
      continue;
    }
    const int f = int(u01(rng) * m.num_triangles()) % m.num_triangles();
    const auto& t = m.triangles[size_t(f)];
    const Vec3 a = m.positions[size_t(t[0])], bb = m.positions[size_t(t[1])], cc = m.positions[size_t(t[2])];
    if (kind < 0.7) {
      double s = u01(rng), r = u01(rng);
      if (s + r > 1) {
        s = 1 - s;
        r = 1 - r;
      }
      const Vec3 n = m.face_cross(f).normalized();
      const double off = std::pow(10.0, -1.0 - 11.0 * u01(rng)) * diag * (u01(rng) < 0.5 ? -1 : 1);
      pts.push_back(a + s * (bb - a) + r * (cc - a) + off * n);
    } else {
      const double s = 6 * u01(rng) - 3, r = 6 * u01(rng) - 3;
      pts.push_back(a + s * (bb - a) + r * (cc - a));
    }
  }
  return pts;
}

}  // namespace qsil::test
