/// @file slices_test.cpp
/// The single-node rejection tests on the canonical patches of `qsil slices` ([QSS] Fig. 7), on
/// two planes each (the command's defaults, 96 x 96 points) plus a plane through the patch:
/// - zero false rejects for quadric, quadric-box, vsphere and vsphere-solid;
/// - the quadric test accepts a subset of what quadric-box accepts (by construction: it runs
///   after the box test), and the hollow v-sphere a subset of the solid one;
/// - the default Hough origin sees no patch edge as a silhouette (the v-sphere test applies).
/// And the commands themselves: `qsil slices --patch sphere` and `qsil candidates` on a small
/// scene exit 0 and write their PNGs and summaries.

#include "qsil/study/canonical_patch.h"

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace qsil::study {
namespace {

struct Rates {
  static constexpr int kTests = int(kRejectionMethods.size());
  long long no_sil = 0, fa[kTests] = {}, fr[kTests] = {}, q_not_box = 0, hollow_not_solid = 0;
};

Rates slice(const PatchTests& t, const Vec3& centre, double h, double extent, int n) {
  Rates r;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const Vec3 p(centre.x() + ((x + 0.5) / n - 0.5) * extent, centre.y() + ((y + 0.5) / n - 0.5) * extent, h);
      const SliceVerdict v = t.evaluate(p);
      r.no_sil += !v.truth;
      for (int k = 0; k < Rates::kTests; ++k) {
        r.fa[k] += !v.truth && v.accept[size_t(k)];
        r.fr[k] += v.truth && !v.accept[size_t(k)];
      }
      r.q_not_box += v.accepts(Method::Quadric) && !v.accepts(Method::QuadricBox);
      r.hollow_not_solid += v.accepts(Method::VSphere) && !v.accepts(Method::VSphereSolid);
    }
  return r;
}

void check_patch(PatchKind kind, const Vec3& centre, std::initializer_list<double> heights) {
  const TriangleMesh mesh = make_canonical_patch(kind);
  EXPECT_GT(mesh.num_triangles(), 300);
  EXPECT_LT(mesh.num_triangles(), 500);
  const PatchTests t = PatchTests::from_mesh(mesh, PatchTests::default_origin(mesh));
  EXPECT_EQ(t.origin_silhouettes(), 0);
  EXPECT_GT(t.num_edges(), 300);
  for (double h : heights) {
    const Rates r = slice(t, centre, h, 4.0, 96);
    for (int k = 0; k < Rates::kTests; ++k)
      EXPECT_EQ(r.fr[k], 0) << method_name(kRejectionMethods[size_t(k)]) << " at h = " << h;
    EXPECT_EQ(r.q_not_box, 0) << "quadric accepts what quadric-box rejects, h = " << h;
    EXPECT_EQ(r.hollow_not_solid, 0) << "hollow accepts what solid rejects, h = " << h;
    std::printf("[%s h=%.2f] false-accept rates: quadric %.3f quadric-box %.3f vsphere %.3f vsphere-solid %.3f\n",
                kind == PatchKind::Sphere ? "sphere" : "torus", h, double(r.fa[0]) / std::max(1LL, r.no_sil),
                double(r.fa[1]) / std::max(1LL, r.no_sil), double(r.fa[2]) / std::max(1LL, r.no_sil),
                double(r.fa[3]) / std::max(1LL, r.no_sil));
  }
}

TEST(Slices, SpherePatchSoundAndNested) { check_patch(PatchKind::Sphere, Vec3(0, 0, 0), {0.9, 2.0, 0.5}); }
TEST(Slices, TorusPatchSoundAndNested) { check_patch(PatchKind::Torus, Vec3(0.7, 0.7, 0), {1.5, 2.5, 0.1}); }

// Runs `qsil ARGS` from the repository root (scene paths are relative to it); returns the exit code.
int run(const std::string& args) {
  const std::string cmd =
      "cd '" + std::string(QSIL_SOURCE_DIR) + "' && " + std::string(QSIL_CLI_PATH) + " " + args + " > /dev/null 2>&1";
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

TEST(Slices, CommandWritesImagesAndSummaries) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "qsil-slices-test";
  fs::remove_all(dir);
  ASSERT_EQ(run("slices --patch torus --resolution 40 --no-grid --out-dir " + dir.string()), 0);
  for (const char* name : {"quadric", "quadric-box", "vsphere", "vsphere-solid"})
    for (int k = 1; k <= 2; ++k)
      EXPECT_TRUE(fs::exists(dir / (std::string(name) + "-plane" + std::to_string(k) + ".png")));
  EXPECT_TRUE(fs::exists(dir / "summary.json"));
  EXPECT_TRUE(fs::exists(dir / "summary.csv"));
  EXPECT_EQ(run("slices --patch cone"), 2);
  fs::remove_all(dir);
}

TEST(Candidates, CommandWritesImagesAndSummaries) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "qsil-candidates-test";
  fs::remove_all(dir);
  // spot-mirror at 64x64: the centre pixel sees the mirror (Spot in it).
  ASSERT_EQ(
      run("candidates scenes/spot-mirror.xml -D res=64 --pixel 32,32 --size 96 --no-grid --out-dir " + dir.string()),
      0);
  for (const char* name : {"quadric", "quadric-box", "vsphere", "vsphere-solid", "uniform"}) {
    EXPECT_TRUE(fs::exists(dir / (std::string(name) + "-camera.png")));
    EXPECT_TRUE(fs::exists(dir / (std::string(name) + "-edges.obj")));
  }
  EXPECT_TRUE(fs::exists(dir / "summary.csv"));
  EXPECT_EQ(run("candidates scenes/spot-mirror.xml --pixel 9999,0"), 2);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace qsil::study
