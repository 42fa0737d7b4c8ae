/// @file cmd_slices.cpp
/// `qsil slices` ([QSS] Sec. 5.1, Fig. 7): the verdicts of four rejection tests for one node on
/// two parallel planes, next to the brute-force ground truth.
///
///   qsil slices --patch sphere|torus [--origin X,Y,Z] [--plane-normal X,Y,Z] [--heights H1,H2]
///               [--center X,Y,Z] [--extent E] [--resolution N] [--out-dir DIR] [--no-grid]
///   qsil slices MESH.obj --node ID [...]     (an inner node of the mesh's quadric edge forest)
///
/// Every point x of the plane {x : n.x = h} within the square of side E around the projection of
/// the centre gets ground truth (does a patch edge have (q0.x)(q1.x) <= 0) and the verdict of
/// quadric, quadric-box, vsphere and vsphere-solid (edgetree/canonical_patch.h). Outputs in DIR:
/// <test>-plane<k>.png (colours below), grid.png (labelled, drawn by tools/slices_grid.py with
/// Debian's matplotlib), summary.json and summary.csv (per test and plane: points, points without
/// silhouette, false accepts, false-accept rate = false accepts / points without silhouette,
/// false rejects). A false reject is a soundness bug: it gets its own colour, an error line and
/// exit code 1.

#include "cli_common.h"
#include "commands.h"
#include "qsil/edgetree/canonical_patch.h"
#include "qsil/edgetree/edge_forest.h"
#include "qsil/error.h"
#include "qsil/image.h"
#include "qsil/scene.h"

#include <tbb/parallel_for.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace qsil::cli {
namespace {

using edgetree::kSliceTests;
using edgetree::SliceTest;

/// Colours of the slice images (sRGB).
constexpr std::array<unsigned char, 3> kCorrectReject{225, 225, 225};  // no silhouette, rejected
constexpr std::array<unsigned char, 3> kCorrectAccept{60, 110, 190};   // silhouette, accepted
constexpr std::array<unsigned char, 3> kFalseAccept{245, 150, 30};     // no silhouette, accepted
constexpr std::array<unsigned char, 3> kFalseReject{230, 0, 230};      // silhouette, rejected (bug)

struct SlicesFlags {
  std::string mesh;
  int node = -1;
  std::string patch;
  std::vector<double> origin, normal, heights, center;
  double extent = 0;
  int resolution = 256;
  std::string out_dir;
  bool no_grid = false;
  std::string scripts_dir;
};

Vec3 vec3_of(const std::vector<double>& v, const char* flag) {
  if (v.size() != 3) throw Error(std::string(flag) + ": expected X,Y,Z");
  return Vec3(v[0], v[1], v[2]);
}

struct PlaneStats {
  long long points = 0, no_sil = 0;
  std::array<long long, kSliceTests> false_accepts{}, false_rejects{}, accepts{};
};

int run_slices(const SlicesFlags& f) {
  namespace fs = std::filesystem;
  // ---- The node.
  TriangleMesh mesh;
  edgetree::EdgeForest forest;
  std::string label;
  Vec3 center, normal(0, 0, 1);
  double extent = 0;
  std::array<double, 2> heights{};
  if (!f.patch.empty()) {
    if (!f.mesh.empty()) throw Error("slices: give either MESH.obj --node ID or --patch, not both");
    const auto kind = edgetree::parse_patch_kind(f.patch);
    mesh = edgetree::make_canonical_patch(kind);
    label = f.patch;
    if (kind == edgetree::PatchKind::Sphere) {
      center = Vec3(0, 0, 0);
      heights = {0.9, 2.0};  // through the cap (inside: no silhouette) and above it
      extent = 4.0;
    } else {
      center = Vec3(0.7, 0.7, 0);
      heights = {1.5, 2.5};  // above the patch: regions without silhouettes exist
      extent = 4.0;
    }
  } else {
    if (f.mesh.empty()) throw Error("slices: give MESH.obj --node ID or --patch sphere|torus");
    if (f.node < 0) throw Error("slices: --node ID is required with a mesh");
    mesh = load_obj(f.mesh);
    const edgetree::ForestShapeInput in{&mesh, 0};
    forest = edgetree::EdgeForest::build(std::span(&in, 1));
    if (f.node >= int(forest.nodes().size()) || forest.node(f.node).is_leaf())
      throw Error("--node " + std::to_string(f.node) + ": not an inner node (the forest has " +
                  std::to_string(forest.nodes().size()) + " nodes)");
    label = fs::path(f.mesh).stem().string() + "-node" + std::to_string(f.node);
    const Box3& b = forest.node(f.node).bp;
    center = b.center();
    heights = {b.hi.z() + 0.1 * b.diagonal(), b.hi.z() + 0.5 * b.diagonal()};
    extent = 3.0 * b.diagonal();
  }
  if (!f.center.empty()) center = vec3_of(f.center, "--center");
  if (!f.normal.empty()) normal = vec3_of(f.normal, "--plane-normal");
  if (!(normal.norm() > 0)) throw Error("--plane-normal: zero vector");
  normal.normalize();
  if (!f.heights.empty()) {
    if (f.heights.size() != 2) throw Error("--heights: expected H1,H2");
    heights = {f.heights[0], f.heights[1]};
  }
  if (f.extent > 0) extent = f.extent;
  if (f.resolution < 2 || f.resolution > 4096) throw Error("--resolution: expected 2..4096");
  const Vec3 o = f.origin.empty() ? edgetree::PatchTests::default_origin(mesh) : vec3_of(f.origin, "--origin");
  const edgetree::PatchTests tests = f.patch.empty() ? edgetree::PatchTests::from_forest_node(forest, f.node, o)
                                                     : edgetree::PatchTests::from_mesh(mesh, o);
  const fs::path dir = f.out_dir.empty() ? fs::path("out") / ("slices-" + label) : fs::path(f.out_dir);
  fs::create_directories(dir);
  // ---- Evaluate both planes.
  const int N = f.resolution;
  const Frame plane_frame(normal);
  std::array<PlaneStats, 2> stats;
  for (int k = 0; k < 2; ++k) {
    const Vec3 c = center - (normal.dot(center) - heights[size_t(k)]) * normal;
    std::vector<edgetree::SliceVerdict> v(size_t(N) * N);
    tbb::parallel_for(0, N, [&](int y) {
      for (int x = 0; x < N; ++x) {
        const Vec3 p = c + ((x + 0.5) / N - 0.5) * extent * plane_frame.s + (0.5 - (y + 0.5) / N) * extent * plane_frame.t;
        v[size_t(y) * N + x] = tests.evaluate(p);
      }
    });
    PlaneStats& st = stats[size_t(k)];
    for (int t = 0; t < kSliceTests; ++t) {
      std::vector<unsigned char> rgb(size_t(N) * N * 3);
      for (size_t i = 0; i < v.size(); ++i) {
        const bool truth = v[i].truth, acc = v[i].accept[t];
        const auto& col = truth ? (acc ? kCorrectAccept : kFalseReject) : (acc ? kFalseAccept : kCorrectReject);
        for (int ch = 0; ch < 3; ++ch) rgb[3 * i + size_t(ch)] = col[size_t(ch)];
        st.false_accepts[size_t(t)] += !truth && acc;
        st.false_rejects[size_t(t)] += truth && !acc;
        st.accepts[size_t(t)] += acc;
      }
      write_png(dir / (std::string(edgetree::slice_test_name(SliceTest(t))) + "-plane" + std::to_string(k + 1) + ".png"),
                N, N, rgb);
    }
    st.points = (long long)v.size();
    for (const auto& x : v) st.no_sil += !x.truth;
  }
  // ---- Summaries.
  auto rate = [](long long a, long long b) { return b > 0 ? double(a) / double(b) : 0.0; };
  std::ostringstream js, csv;
  js.precision(9);
  csv.precision(9);
  js << "{\n  \"node\": \"" << label << "\",\n  \"edges\": " << tests.num_edges()
     << ",\n  \"hough_origin\": [" << o.x() << ", " << o.y() << ", " << o.z() << "],\n  \"origin_silhouettes\": "
     << tests.origin_silhouettes() << ",\n  \"plane_normal\": [" << normal.x() << ", " << normal.y() << ", "
     << normal.z() << "],\n  \"extent\": " << extent << ",\n  \"resolution\": " << N << ",\n  \"planes\": [\n";
  csv << "plane,height,test,points,no_silhouette,false_accepts,false_accept_rate,false_rejects\n";
  long long total_false_rejects = 0;
  for (int k = 0; k < 2; ++k) {
    const PlaneStats& st = stats[size_t(k)];
    js << "    {\"plane\": " << k + 1 << ", \"height\": " << heights[size_t(k)] << ", \"points\": " << st.points
       << ", \"no_silhouette\": " << st.no_sil << ", \"tests\": {";
    for (int t = 0; t < kSliceTests; ++t) {
      const char* name = edgetree::slice_test_name(SliceTest(t));
      js << (t ? ", " : "") << "\"" << name << "\": {\"false_accepts\": " << st.false_accepts[size_t(t)]
         << ", \"false_accept_rate\": " << rate(st.false_accepts[size_t(t)], st.no_sil)
         << ", \"false_rejects\": " << st.false_rejects[size_t(t)] << ", \"image\": \"" << name << "-plane" << k + 1
         << ".png\"}";
      csv << k + 1 << "," << heights[size_t(k)] << "," << name << "," << st.points << "," << st.no_sil << ","
          << st.false_accepts[size_t(t)] << "," << rate(st.false_accepts[size_t(t)], st.no_sil) << ","
          << st.false_rejects[size_t(t)] << "\n";
      total_false_rejects += st.false_rejects[size_t(t)];
      std::printf("slices %s plane %d (h = %g): %-13s false-accept rate %.4f (%lld of %lld), false rejects %lld\n",
                  label.c_str(), k + 1, heights[size_t(k)], name, rate(st.false_accepts[size_t(t)], st.no_sil),
                  st.false_accepts[size_t(t)], st.no_sil, st.false_rejects[size_t(t)]);
    }
    js << "}}" << (k == 0 ? "," : "") << "\n";
  }
  js << "  ],\n  \"false_rejects\": " << total_false_rejects << "\n}\n";
  auto write_text = [](const fs::path& p, const std::string& s) {
    const fs::path tmp = p.string() + ".tmp";
    {
      std::ofstream out(tmp);
      out << s;
      if (!out) throw Error(p.string() + ": cannot write");
    }
    fs::rename(tmp, p);
  };
  write_text(dir / "summary.json", js.str());
  write_text(dir / "summary.csv", csv.str());
  if (tests.origin_silhouettes() > 0)
    std::fprintf(stderr, "slices: warning: %d edges are silhouettes from the Hough origin: the v-sphere methods keep "
                 "them in a plain tree and accept every point\n", tests.origin_silhouettes());
  // ---- The labelled grid (matplotlib from Debian's python3; the C++ side draws no text).
  if (!f.no_grid) {
    if (run_python_script("slices", "slices_grid.py", {(dir / "summary.json").string(), (dir / "grid.png").string()},
                          f.scripts_dir) != 0)
      std::fprintf(stderr, "slices: warning: the grid image was not drawn\n");
  }
  std::printf("slices: %s, %d edges, %dx%d points per plane -> %s\n", label.c_str(), tests.num_edges(), N, N,
              dir.string().c_str());
  if (total_false_rejects > 0) {
    std::fprintf(stderr, "slices: error: %lld false rejects (a rejection test is unsound; magenta in the images)\n",
                 total_false_rejects);
    return 1;
  }
  return 0;
}

const CommandRegistrar registrar{{"slices", "False accepts of four rejection tests on two planes through one node ([QSS] Fig. 7)",
  [](CLI::App& app) -> std::function<int()> {
    auto f = std::make_shared<SlicesFlags>();
    app.add_option("mesh", f->mesh, "Mesh (.obj) whose forest node --node is shown");
    app.add_option("--node", f->node, "Inner node id of the mesh's quadric edge forest");
    app.add_option("--patch", f->patch, "Canonical patch instead of a mesh: sphere (spherical cap) or torus (toroidal patch)");
    app.add_option("--origin", f->origin, "Hough origin X,Y,Z of the v-sphere tests (default: 3 diagonals along the mean normal)")
        ->delimiter(',')->expected(3);
    app.add_option("--plane-normal", f->normal, "Normal X,Y,Z of the two planes (default 0,0,1)")->delimiter(',')->expected(3);
    app.add_option("--heights", f->heights, "Plane offsets H1,H2 along the normal (n.x = H)")->delimiter(',')->expected(2);
    app.add_option("--center", f->center, "Centre X,Y,Z of the squares (projected onto each plane)")->delimiter(',')->expected(3);
    app.add_option("--extent", f->extent, "Side of the square on each plane (scene units)");
    app.add_option("--resolution", f->resolution, "Points per side")->capture_default_str();
    app.add_option("--out-dir", f->out_dir, "Output directory (default out/slices-<patch>)");
    app.add_flag("--no-grid", f->no_grid, "Skip the labelled grid image (no Python)");
    add_scripts_dir_option(app, f->scripts_dir);
    return [f] { return run_slices(*f); };
  }}};

}  // namespace
}  // namespace qsil::cli
