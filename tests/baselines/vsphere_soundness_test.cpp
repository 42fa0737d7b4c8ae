/// @file vsphere_soundness_test.cpp
/// Soundness of the v-sphere rejection test by brute force ([QSS] App. F; docs/architecture.md §7, §9): for
/// every node of Li's Hough-space tree (inner nodes and one-edge leaves) of spot, torus, bunny and
/// a subdivided cube, and many shading points (around the mesh, near the surface, on triangle
/// planes; plus the Hough origin itself and points near it), whenever the node's edges include a
/// silhouette (edge_is_silhouette, double) both the hollow and the solid test must accept: zero
/// false rejects. And the hollow test accepts a subset of what the solid one accepts (the
/// corrected test only removes accepts). Two Hough origins per mesh: camera-like (outside) and
/// the mesh centre (inside). Fixed seeds; ~1e3 points per mesh and origin.

#include "baselines/baseline_test_util.h"
#include "qsil/edgetree/edge_forest.h"
#include "qsil/edgetree/vsphere_tree.h"

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cstdio>

namespace qsil::edgetree {
namespace {

using namespace qsil::baselines_test;

struct Counts {
  long long with_sil = 0, no_sil = 0;
  long long fr_hollow = 0, fr_solid = 0, hollow_not_solid = 0;
  long long fa_hollow = 0, fa_solid = 0;
};

Counts check_tree(const VSphereTree& t, const std::vector<Vec3>& pts) {
  std::atomic<long long> ws{0}, ns{0}, frh{0}, frs{0}, hns{0}, fah{0}, fas{0};
  const int N = int(t.nodes().size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, pts.size(), 16), [&](const auto& r) {
    std::vector<char> has(static_cast<size_t>(N));
    Counts c;
    for (size_t k = r.begin(); k != r.end(); ++k) {
      const Vec3& p = pts[k];
      for (int i = N - 1; i >= 0; --i) {  // preorder: children after their parent
        const VSphereNode& n = t.node(i);
        has[size_t(i)] = n.is_leaf() ? edge_is_silhouette(*t.edges()[size_t(n.edge)], p)
                                     : (has[size_t(n.child[0])] || has[size_t(n.child[1])]);
        if (!n.hough) continue;
        const bool h = t.may_have_silhouette(i, p, VSphereTest::Hollow);
        const bool s = t.may_have_silhouette(i, p, VSphereTest::Solid);
        c.hollow_not_solid += h && !s;
        if (has[size_t(i)]) {
          ++c.with_sil;
          c.fr_hollow += !h;
          c.fr_solid += !s;
        } else {
          ++c.no_sil;
          c.fa_hollow += h;
          c.fa_solid += s;
        }
      }
    }
    // clang-format off
    ws += c.with_sil; ns += c.no_sil; frh += c.fr_hollow; frs += c.fr_solid; hns += c.hollow_not_solid;
    fah += c.fa_hollow; fas += c.fa_solid;
    // clang-format on
  });
  return {ws.load(), ns.load(), frh.load(), frs.load(), hns.load(), fah.load(), fas.load()};
}

/// `rejects_some`: also require that the test rejects something (not for the axis-aligned cube:
/// the Hough box of two axis-aligned planes contains the Hough origin, which lies on every
/// v-sphere, so Li's test can never reject there; a property of the method, not a bug).
void expect_sound(const TriangleMesh& mesh, int npoints, unsigned seed, const std::string& name,
                  bool rejects_some = true) {
  const ForestShapeInput in{&mesh, 0};
  const EdgeForest f = EdgeForest::build(std::span(&in, 1));
  const Box3 b = mesh.bounds();
  for (const Vec3& o : {camera_like_origin(mesh), b.center()}) {
    const VSphereTree t = VSphereTree::build(f, o);
    ASSERT_GT(t.hough_edges(), 0) << name;
    std::vector<Vec3> pts = shading_points(mesh, npoints, seed);
    pts.push_back(o);
    for (int i = 0; i < 20; ++i) pts.push_back(o + b.diagonal() * std::pow(10.0, -i * 0.6) * Vec3(0.3, -0.5, 0.2));
    const Counts c = check_tree(t, pts);
    EXPECT_GT(c.with_sil, 0) << name;
    EXPECT_EQ(c.fr_hollow, 0) << name << ": hollow v-sphere false rejects of " << c.with_sil;
    EXPECT_EQ(c.fr_solid, 0) << name << ": solid v-sphere false rejects of " << c.with_sil;
    EXPECT_EQ(c.hollow_not_solid, 0) << name << ": hollow accepts that solid rejects";
    if (rejects_some) {
      EXPECT_LT(c.fa_hollow, c.no_sil) << name;  // it rejects something at all
    }
    std::printf(
        "[%s, o=(%.2f,%.2f,%.2f)] plain %d / hough %d edges; %lld (node, point) pairs with a silhouette; "
        "false-accept rate hollow %.3f solid %.3f\n",
        name.c_str(), o.x(), o.y(), o.z(), t.plain_edges(), t.hough_edges(), c.with_sil,
        c.no_sil ? double(c.fa_hollow) / c.no_sil : 0.0, c.no_sil ? double(c.fa_solid) / c.no_sil : 0.0);
  }
}

TEST(BaselineSoundness, VSphereSpot) { expect_sound(test_mesh("spot.obj"), 1000, 21, "spot"); }
TEST(BaselineSoundness, VSphereTorus) { expect_sound(test_mesh("torus.obj"), 1000, 22, "torus"); }
TEST(BaselineSoundness, VSphereBunny) { expect_sound(test_mesh("bunny.obj"), 600, 23, "bunny"); }
TEST(BaselineSoundness, VSphereCube) { expect_sound(make_cube(8), 1000, 24, "cube", false); }
TEST(BaselineSoundness, VSphereTranslatedAndScaled) {
  TriangleMesh m = test_mesh("spot.obj");
  for (auto& p : m.positions) p = p + Vec3(1e4, -1e4, 1e4);
  expect_sound(m, 400, 25, "spot+1e4");
  TriangleMesh s = test_mesh("torus.obj");
  for (auto& p : s.positions) p = p * 1e-4;
  expect_sound(s, 400, 26, "torus*1e-4");
}

}  // namespace
}  // namespace qsil::edgetree
