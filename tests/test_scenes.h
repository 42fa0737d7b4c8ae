#pragma once
// Scenes built in code for tests: an icosphere, a camera looking at the origin.
#include "qsil/scene.h"

#include <map>

namespace qsil::test {

/// Unit-radius icosphere centred at c with radius r, `subdiv` Loop-style midpoint subdivisions
/// (20 * 4^subdiv triangles), outward counter-clockwise winding.
inline TriangleMesh icosphere(int subdiv, const Vec3& c = Vec3::Zero(), double r = 1.0) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> v = {{-1, t, 0},  {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p.normalize();
  std::vector<Eigen::Vector3i> f = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                    {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                                    {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (int s = 0; s < subdiv; ++s) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = int(v.size()) - 1;
    };
    std::vector<Eigen::Vector3i> g;
    for (const auto& tri : f) {
      const int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), cc = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, cc});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], cc, b});
      g.push_back({a, b, cc});
    }
    f = std::move(g);
  }
  TriangleMesh m;
  for (auto& p : v) m.positions.push_back(c + r * p);
  m.triangles = f;
  m.normals = vertex_normals(m);
  return m;
}

/// A camera at `origin` looking at `target` (Mitsuba lookat with up +y).
inline Camera look_at(const Vec3& origin, const Vec3& target, double fov_deg, int w, int h, int spp) {
  Camera cam;
  cam.to_world = qsil::look_at(origin, target, Vec3(0, 1, 0));
  cam.fov_deg = fov_deg;
  cam.width = w;
  cam.height = h;
  cam.spp = spp;
  return cam;
}

/// A diffuse sphere (face normals: a convex polyhedron, so every reflected ray escapes) inside a
/// constant environment of radiance L.
inline Scene furnace_scene(double albedo, double L, int res, int spp) {
  Scene s;
  s.bsdfs.push_back(BSDFDesc{});
  s.bsdfs[0].reflectance = Color::Constant(albedo);
  Shape sphere;
  sphere.id = "sphere";
  sphere.type = "obj";
  sphere.mesh = icosphere(3);
  sphere.mesh.normals.clear();
  sphere.face_normals = true;
  sphere.bsdf = 0;
  s.shapes.push_back(sphere);
  s.environment.type = Environment::Type::Constant;
  s.environment.radiance = Color::Constant(L);
  s.camera = look_at(Vec3(0, 0, 4), Vec3(0, 0, 0), 40, res, res, spp);
  s.max_depth = -1;
  return s;
}

}  // namespace qsil::test
