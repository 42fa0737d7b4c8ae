/// @file cmd_candidates.cpp
/// `qsil candidates` ([QSS] Sec. 5.1, Fig. 8): for one shading point, every edge each method can
/// sample (find_candidates, qsil/study/candidates.h, which documents the study and its
/// outputs).
///
///   qsil candidates SCENE.xml (--pixel X,Y | --point X,Y,Z --normal X,Y,Z)
///                   [--methods quadric,quadric-box,vsphere,vsphere-solid,uniform] [--shapes ID,...]
///                   [--size N] [--out-dir DIR] [--no-grid] [-D name=value]...
///
/// DIR/grid.png is labelled by tools/candidates_grid.py (matplotlib).

#include "cli_common.h"
#include "commands.h"
#include "qsil/study/candidates.h"

#include <cstdio>
#include <filesystem>

namespace qsil::cli {
namespace {

struct Flags {
  std::string scene;
  std::vector<std::string> defines;
  CandidatesOptions study;
  std::vector<std::string> methods;
  int size = 768;
  ChartOutputFlags chart;
};

int run(const Flags& f) {
  CandidatesOptions o = f.study;
  if (!f.methods.empty()) {
    o.methods.clear();
    for (const std::string& m : f.methods) o.methods.push_back(parse_method(m, "--methods", kEdgeSamplingMethods));
  }
  const Scene scene = load_scene_with_flags(f.scene, f.defines);
  const CandidatesReport rep = find_candidates(scene, o);
  const std::filesystem::path dir =
      f.chart.out_dir.empty() ? std::filesystem::path("out") / "candidates" : std::filesystem::path(f.chart.out_dir);
  write_candidates(scene, rep, f.scene, dir, f.size);
  for (const MethodCandidates& m : rep.methods)
    std::printf(
        "candidates %-13s %6lld candidates, %5lld silhouettes (%lld facing the upper hemisphere), "
        "non-silhouette mass %.4f, dead-end mass %.4f%s\n",
        std::string(method_name(m.method)).c_str(), m.candidates, m.silhouettes, m.upper, m.non_silhouette_mass,
        m.dead_end_mass, m.leaf_edges >= 0 ? (", leaf edges tested " + std::to_string(m.leaf_edges)).c_str() : "");
  if (!f.chart.no_grid &&
      run_python_script("candidates", "candidates_grid.py",
                        {(dir / "summary.json").string(), (dir / "grid.png").string()}, f.chart.scripts_dir) != 0)
    std::fprintf(stderr, "candidates: warning: the grid image was not drawn\n");
  std::printf("candidates: %s at %s, p = (%.4f, %.4f, %.4f), %lld true silhouettes (%lld upper) -> %s\n",
              f.scene.c_str(), rep.where.c_str(), rep.p.x(), rep.p.y(), rep.p.z(), rep.true_silhouettes, rep.true_upper,
              dir.string().c_str());
  return 0;
}

const CommandRegistrar registrar{
    {"candidates", "Edges each method can sample from one shading point ([QSS] Fig. 8)",
     [](CLI::App& app) -> std::function<int()> {
       auto f = std::make_shared<Flags>();
       add_scene_options(app, f->scene, f->defines);
       app.add_option("--pixel", f->study.pixel, "Pixel X,Y whose first hit is the shading point")
           ->delimiter(',')
           ->expected(2);
       app.add_option("--point", f->study.point, "Shading point X,Y,Z (with --normal)")->delimiter(',')->expected(3);
       app.add_option("--normal", f->study.normal, "Shading normal X,Y,Z (with --point)")->delimiter(',')->expected(3);
       app.add_option("--methods", f->methods, "Methods, comma separated: " + method_list(kEdgeSamplingMethods))
           ->delimiter(',');
       app.add_option("--shapes", f->study.shapes, "Eligible shape ids, comma separated (default: every shape)")
           ->delimiter(',');
       app.add_option("--size", f->size, "Larger side of the pictures in pixels")
           ->capture_default_str()
           ->check(qsil::cli::positive_number());
       add_chart_output_options(app, f->chart, "out/candidates");
       return [f] { return run(*f); };
     }}};

}  // namespace
}  // namespace qsil::cli
