/// @file ray_tracer_test.cpp
/// The Embree wrapper never hands Embree an invalid ray: non-finite or huge origins or
/// directions, zero directions and NaN lengths are misses ("not occluded") and are counted, where
/// Embree would abort the process on its `ray.valid()` assertion. And the gradient of the scene
/// that aborted (spot-mirror with one Spot vertex at 1e30, placed in memory past the loader that
/// now refuses it) completes. And rays that pass through back faces (IgnoreSet::through_back_faces,
/// which keep the radiance of smooth-shaded meshes continuous across edges) skip exactly the back sides of one-sided
/// surfaces.

#include "qsil/ray_tracer.h"
#include "qsil/integrators/estimator.h"
#include "qsil/scene.h"
#include "test_data.h"
#include "test_scenes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>

namespace qsil {
namespace {

Scene sphere_scene() {
  Scene s;
  s.bsdfs.push_back(BSDFDesc{});
  Shape sphere;
  sphere.id = "sphere";
  sphere.type = "obj";
  sphere.mesh = test::icosphere(2);
  sphere.bsdf = 0;
  s.shapes.push_back(sphere);
  return s;
}

TEST(RayTracer, ValidRaysHitAsBefore) {
  const Scene s = sphere_scene();
  const RayTracer tracer(s);
  const Hit hit = tracer.intersect(Vec3(0, 0, 4), Vec3(0, 0, -1));
  ASSERT_TRUE(hit.valid());
  EXPECT_NEAR(hit.t, 3.0, 0.05);
  EXPECT_TRUE(tracer.occluded(Vec3(0, 0, 4), Vec3(0, 0, -1), 10.0));
  EXPECT_FALSE(tracer.occluded(Vec3(0, 0, 4), Vec3(0, 0, -1), 2.0));
  EXPECT_EQ(tracer.invalid_rays(), 0u);
  // A far but valid origin (within Embree's bound) is not refused.
  EXPECT_TRUE(ray_is_valid(Vec3(1e17, 0, 0), Vec3(-1, 0, 0), kInf));
}

TEST(RayTracer, InvalidRaysAreCountedMisses) {
  const Scene s = sphere_scene();
  const RayTracer tracer(s);
  const uint64_t total_before = RayTracer::total_invalid_rays();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Vec3 toward(0, 0, -1);
  struct Ray {
    Vec3 origin, dir;
    double tmax;
  };
  const Ray bad[] = {
      {Vec3(1e30, 1e30, -1e30), Vec3(-1, -1, 1).normalized(), kInf},  // a vertex at 1e30 as an origin
      {Vec3(0, 0, 2e18), toward, kInf},                               // just beyond Embree's 1.844e18
      {Vec3(0, 0, 4), Vec3(0, 0, -1e19), kInf},                       // an unnormalised huge direction
      {Vec3(0, 0, kInf), toward, kInf},
      {Vec3(nan, 0, 4), toward, kInf},
      {Vec3(0, 0, 4), Vec3(0, nan, -1), kInf},
      {Vec3(0, 0, 4), Vec3(0, 0, 1e-60), kInf},  // rounds to a zero float direction
      {Vec3(0, 0, 4), toward, nan},
  };
  int n = 0;
  for (const Ray& r : bad) {
    EXPECT_FALSE(ray_is_valid(r.origin, r.dir, r.tmax)) << n;
    EXPECT_FALSE(tracer.intersect(r.origin, r.dir, r.tmax).valid()) << n;
    EXPECT_FALSE(tracer.occluded(r.origin, r.dir, r.tmax)) << n;
    n += 2;
  }
  EXPECT_EQ(tracer.invalid_rays(), uint64_t(n));
  EXPECT_EQ(RayTracer::total_invalid_rays() - total_before, uint64_t(n));
}

// A vertex far out once aborted the process: grad of spot-mirror with Spot's first OBJ vertex (0.348799, -0.334989,
// -0.0832331) at (1e30, 1e30, -1e30) made Embree assert on a ray leaving that vertex's triangles.
// The loader now refuses such a mesh, so the scene is loaded intact and the vertex moved in
// memory as the old loader had it (Spot has no to_world; triangles that became zero-area dropped);
// the render must finish, refusing the invalid rays instead of aborting.
TEST(RayTracer, GradientWithAHugeVertexCompletes) {
  Scene scene = load_scene(test::data_file("scenes/spot-mirror.xml"), {{"res", "16"}, {"spp", "1"}});
  const int spot = scene.find_shape("spot");
  ASSERT_GE(spot, 0);
  TriangleMesh& mesh = scene.shapes[size_t(spot)].mesh;
  const Vec3 original(0.348799, -0.334989, -0.0832331);
  const auto first = std::min_element(mesh.positions.begin(), mesh.positions.end(), [&](const Vec3& a, const Vec3& b) {
    return (a - original).squaredNorm() < (b - original).squaredNorm();
  });
  ASSERT_LT((*first - original).norm(), 1e-9) << "Spot's first OBJ vertex";
  *first = Vec3(1e30, 1e30, -1e30);
  std::vector<Eigen::Vector3i> kept;
  for (int f = 0; f < mesh.num_triangles(); ++f)
    if (mesh.area(f) > 0) kept.push_back(mesh.triangles[size_t(f)]);
  mesh.triangles = kept;
  mesh.normals = vertex_normals(mesh);
  const std::vector<ParameterSpec> params{parse_parameter("spot:translate:0,1,0", scene)};
  RenderOptions o;
  o.progress = false;
  o.threads = 1;
  const uint64_t before = RayTracer::total_invalid_rays();
  const RenderResult r = Estimator(scene, EstimatorConfig::gradient(params)).run(o);
  EXPECT_EQ(r.film.width(), 16);
  EXPECT_GT(RayTracer::total_invalid_rays(), before) << "rays from the huge triangles were refused";
}

}  // namespace
namespace {

/// One unit quad in the plane z = 0 facing +z (counter-clockwise seen from +z), optionally
/// twosided, and a second, one-sided quad at z = -1 facing +z.
Scene two_quads(bool twosided) {
  Scene s;
  s.bsdfs.push_back(BSDFDesc{});
  s.bsdfs[0].twosided = twosided;
  s.bsdfs.push_back(BSDFDesc{});
  for (double z : {0.0, -1.0}) {
    Shape q;
    q.type = "obj";
    q.mesh.positions = {Vec3(-1, -1, z), Vec3(1, -1, z), Vec3(1, 1, z), Vec3(-1, 1, z)};
    q.mesh.triangles = {Eigen::Vector3i(0, 1, 2), Eigen::Vector3i(0, 2, 3)};
    q.bsdf = z == 0.0 ? 0 : 1;
    s.shapes.push_back(q);
  }
  return s;
}

}  // namespace

// A ray meets the front side of the upper quad from above, and the back side from below; with
// through_back_faces the back side of a one-sided quad is skipped (and the ray goes on), the
// front side never is, and a twosided quad is never skipped. This pins Embree's normal
// orientation, which the filter relies on (counter-clockwise = front, as the meshes are wound).
TEST(RayTracer, ThroughBackFacesSkipsOnlyBackSidesOfOneSidedSurfaces) {
  const Scene one = two_quads(false);
  const RayTracer rt(one);
  IgnoreSet pass;
  pass.through_back_faces = true;
  // From above, downward: front of quad 0 (z = 0) with or without the flag.
  EXPECT_EQ(rt.intersect(Vec3(0.1, 0.2, 1), Vec3(0, 0, -1)).shape, 0);
  EXPECT_EQ(rt.intersect(Vec3(0.1, 0.2, 1), Vec3(0, 0, -1), kInf, pass).shape, 0);
  EXPECT_TRUE(rt.occluded(Vec3(0.1, 0.2, 1), Vec3(0, 0, -1), 2.0, pass));
  // From between the quads, upward: the back side of quad 0.
  const Hit back = rt.intersect(Vec3(0.1, 0.2, -0.5), Vec3(0, 0, 1));
  EXPECT_EQ(back.shape, 0);
  EXPECT_NEAR(back.t, 0.5, 1e-6);
  EXPECT_FALSE(rt.intersect(Vec3(0.1, 0.2, -0.5), Vec3(0, 0, 1), kInf, pass).valid());
  EXPECT_TRUE(rt.occluded(Vec3(0.1, 0.2, -0.5), Vec3(0, 0, 1), 2.0));
  EXPECT_FALSE(rt.occluded(Vec3(0.1, 0.2, -0.5), Vec3(0, 0, 1), 2.0, pass));
  // From below both, upward through the back of quad 1 and quad 0: nothing with the flag.
  EXPECT_EQ(rt.intersect(Vec3(0.1, 0.2, -2), Vec3(0, 0, 1)).shape, 1);
  EXPECT_FALSE(rt.intersect(Vec3(0.1, 0.2, -2), Vec3(0, 0, 1), kInf, pass).valid());
  // A twosided quad 0 stops the ray from behind even with the flag (its back side scatters).
  const Scene two = two_quads(true);
  const RayTracer rt2(two);
  EXPECT_EQ(rt2.intersect(Vec3(0.1, 0.2, -0.5), Vec3(0, 0, 1), kInf, pass).shape, 0);
  // The flag combines with ignored triangles: ignoring both triangles of quad 0 from above
  // leaves the front of quad 1.
  IgnoreSet both = pass;
  both.prims[0] = {0, 0};
  both.prims[1] = {0, 1};
  EXPECT_EQ(rt.intersect(Vec3(0.1, 0.2, 1), Vec3(0, 0, -1), kInf, both).shape, 1);
}

}  // namespace qsil
