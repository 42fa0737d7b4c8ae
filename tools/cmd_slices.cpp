/// @file cmd_slices.cpp
/// `qsil slices` ([QSS] Sec. 5.1, Fig. 7): the verdicts of four rejection tests for one node on
/// two parallel planes, next to the brute-force ground truth (run_slice_study,
/// qsil/study/slice_study.h, which documents the study and its outputs).
///
///   qsil slices --patch sphere|torus [--origin X,Y,Z] [--plane-normal X,Y,Z] [--heights H1,H2]
///               [--center X,Y,Z] [--extent E] [--resolution N] [--out-dir DIR] [--no-grid]
///   qsil slices MESH.obj --node ID [...]     (an inner node of the mesh's quadric edge forest)
///
/// DIR/grid.png is labelled by tools/slices_grid.py (Debian's matplotlib). A false reject is a
/// soundness bug: it gets its own colour, an error line and exit code 1.

#include "cli_common.h"
#include "commands.h"
#include "qsil/study/slice_study.h"

#include <cstdio>
#include <filesystem>

namespace qsil::cli {
namespace {

struct Flags {
  study::SliceStudyOptions study;
  ChartOutputFlags chart;
};

int run(const Flags& f) {
  const study::SliceStudy s = study::run_slice_study(f.study);
  const std::filesystem::path dir =
      f.chart.out_dir.empty() ? std::filesystem::path("out") / ("slices-" + s.label) : std::filesystem::path(f.chart.out_dir);
  study::write_slice_study(s, dir);
  for (int k = 0; k < 2; ++k) {
    const study::PlaneStats& st = s.planes[size_t(k)];
    for (size_t t = 0; t < kRejectionMethods.size(); ++t)
      std::printf("slices %s plane %d (h = %g): %-13s false-accept rate %.4f (%lld of %lld), false rejects %lld\n",
                  s.label.c_str(), k + 1, st.height, std::string(method_name(kRejectionMethods[t])).c_str(),
                  st.no_silhouette > 0 ? double(st.false_accepts[t]) / double(st.no_silhouette) : 0.0,
                  st.false_accepts[t], st.no_silhouette, st.false_rejects[t]);
  }
  if (s.origin_silhouettes > 0)
    std::fprintf(stderr,
                 "slices: warning: %d edges are silhouettes from the Hough origin: the v-sphere methods keep "
                 "them in a plain tree and accept every point\n",
                 s.origin_silhouettes);
  if (!f.chart.no_grid &&
      run_python_script("slices", "slices_grid.py", {(dir / "summary.json").string(), (dir / "grid.png").string()},
                        f.chart.scripts_dir) != 0)
    std::fprintf(stderr, "slices: warning: the grid image was not drawn\n");
  std::printf("slices: %s, %d edges, %dx%d points per plane -> %s\n", s.label.c_str(), s.edges, s.resolution,
              s.resolution, dir.string().c_str());
  if (s.false_rejects() > 0) {
    std::fprintf(stderr, "slices: error: %lld false rejects (a rejection test is unsound; magenta in the images)\n",
                 s.false_rejects());
    return 1;
  }
  return 0;
}

const CommandRegistrar registrar{
    {"slices", "False accepts of four rejection tests on two planes through one node ([QSS] Fig. 7)",
     [](CLI::App& app) -> std::function<int()> {
       auto f = std::make_shared<Flags>();
       study::SliceStudyOptions& s = f->study;
       app.add_option("mesh", s.mesh, "Mesh (.obj) whose forest node --node is shown");
       app.add_option("--node", s.node, "Inner node id of the mesh's quadric edge forest")
           ->check(qsil::cli::non_negative_number());
       app.add_option("--patch", s.patch,
                      "Canonical patch instead of a mesh: sphere (spherical cap) or torus (toroidal patch)");
       app.add_option("--origin", s.origin,
                      "Hough origin X,Y,Z of the v-sphere tests (default: 3 diagonals along the mean normal)")
           ->delimiter(',')
           ->expected(3);
       app.add_option("--plane-normal", s.normal, "Normal X,Y,Z of the two planes (default 0,0,1)")
           ->delimiter(',')
           ->expected(3);
       app.add_option("--heights", s.heights, "Plane offsets H1,H2 along the normal (n.x = H)")
           ->delimiter(',')
           ->expected(2);
       app.add_option("--center", s.center, "Centre X,Y,Z of the squares (projected onto each plane)")
           ->delimiter(',')
           ->expected(3);
       app.add_option("--extent", s.extent, "Side of the square on each plane (scene units)");
       app.add_option("--resolution", s.resolution, "Points per side")->capture_default_str()->check(qsil::cli::positive_number());
       add_chart_output_options(app, f->chart, "out/slices-<patch>");
       return [f] { return run(*f); };
     }}};

}  // namespace
}  // namespace qsil::cli
