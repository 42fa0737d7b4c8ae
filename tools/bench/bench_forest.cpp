/// @file bench_forest.cpp
/// Edge forest benchmark (docs/architecture.md §11), a table printer: for each OBJ given on the
/// command line, or without arguments for the six test meshes of tests/data/meshes/README.md
/// (paths relative to the repository root, so run it from there): edges before/after culling,
/// nodes, unrejectable and box-only
/// inner nodes, build time with 1 and 2 threads (best of 5), bytes per edge, rejection tests per
/// second (quadric and box, inner nodes x random points in a box 3x the mesh's size, one thread),
/// and the false-accept rate (fraction of accepted inner nodes whose patch has no silhouette) of
/// the quadric test vs the dual box alone.

#include "cli_parse.h"
#include "qsil/edgetree/edge_forest.h"
#include "qsil/edgetree/node_rejection.h"
#include "qsil/scene.h"

#include <tbb/global_control.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

using namespace qsil;
using namespace qsil::edgetree;

namespace {
double best_build(const TriangleMesh& m, int threads, EdgeForest* out) {
  tbb::global_control gc(tbb::global_control::max_allowed_parallelism, size_t(threads));
  ForestShapeInput in{&m, 0};
  double best = 1e30;
  for (int r = 0; r < 5; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    EdgeForest f = EdgeForest::build(std::span(&in, 1));
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    if (r == 0 && out) *out = std::move(f);
  }
  return best;
}
}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> meshes;
  CLI::App app{"bench_forest: edge-forest statistics, build times and rejection-test rates per mesh"};
  app.add_option("meshes", meshes, "OBJ files (default: the six test meshes, paths relative to the repository root)");
  if (const auto code = qsil::cli::parse_arguments(app, argc, argv)) return *code;
  if (meshes.empty())
    meshes = {
        "scenes/meshes/spot.obj",      "tests/data/meshes/bob.obj",          "scenes/meshes/bunny.obj",
        "tests/data/meshes/torus.obj", "scenes/stability/meshes/teapot.obj", "scenes/stability/meshes/wingnut.obj"};
  std::printf("%-8s %6s %6s %6s %6s %5s %5s %8s %8s %7s %9s %9s %7s %7s\n", "mesh", "edges", "kept", "nodes", "inner",
              "unrej", "boxo", "build1s", "build2s", "B/edge", "quad/s", "box/s", "FA-quad", "FA-box");
  for (const std::string& path : meshes) {
    TriangleMesh m;
    try {
      m = load_obj(path);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "bench_forest: %s\n", e.what());
      return 2;
    }
    const std::string stem = std::filesystem::path(path).stem().string();
    const char* name = stem.c_str();
    EdgeForest f;
    const double t1 = best_build(m, 1, &f);
    const double t2 = best_build(m, 2, nullptr);
    const ForestShapeStats& st = f.stats()[0];
    // Random points in a box 3x the mesh's size (fixed seed).
    std::mt19937_64 rng(42);
    std::uniform_real_distribution<double> u(-1.5, 1.5);
    const Box3 b = m.bounds();
    std::vector<Vec3> pts;
    for (int i = 0; i < 2000; ++i)
      pts.push_back(b.center() + Vec3(u(rng) * b.extent().x(), u(rng) * b.extent().y(), u(rng) * b.extent().z()));
    std::vector<int> inner;
    for (int i = 0; i < int(f.nodes().size()); ++i)
      if (!f.node(i).is_leaf()) inner.push_back(i);
    long long acc[2] = {0, 0}, fa[2] = {0, 0};
    double secs[2] = {0, 0};
    for (int mode = 0; mode < 2; ++mode) {
      const NodeTest rm = mode == 0 ? NodeTest::DualBoxAndQuadrics : NodeTest::DualBox;
      const auto t0 = std::chrono::steady_clock::now();
      for (const Vec3& p : pts)
        for (int i : inner) acc[mode] += may_have_silhouette(f, i, p, rm);
      secs[mode] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
    for (const Vec3& p : pts)
      for (int i : inner) {
        if (node_has_silhouette(f, i, p)) continue;
        fa[0] += may_have_silhouette(f, i, p, NodeTest::DualBoxAndQuadrics);
        fa[1] += may_have_silhouette(f, i, p, NodeTest::DualBox);
      }
    const double ntests = double(pts.size()) * double(inner.size());
    std::printf("%-8s %6d %6d %6d %6d %5d %5d %8.4f %8.4f %7.1f %9.3g %9.3g %7.3f %7.3f\n", name, st.edges_total,
                st.edges_kept, st.nodes, st.inner_nodes, st.unrejectable, st.box_only, t1, t2,
                double(f.memory_bytes()) / st.edges_kept, ntests / secs[0], ntests / secs[1],
                double(fa[0]) / double(acc[0]), double(fa[1]) / double(acc[1]));
    std::fflush(stdout);
  }
  return 0;
}
