/// @file cmd_forest.cpp
/// `qsil forest MESH.obj|SCENE.xml --stats [--keep-concave] [--threads N] [--min-fit-planes K]`:
/// builds the quadric edge forest [QSS 4] over every shape and prints, per shape, edges per
/// class, edges kept, nodes, unrejectable / box-only / inherited-quadric nodes, tree depth,
/// build time and bytes per edge. Bad input: one-line qsil::Error, exit code 2.

#include "cli_parse.h"
#include "commands.h"
#include "qsil/edgetree/edge_forest.h"
#include "qsil/error.h"
#include "qsil/scene.h"

#include <tbb/global_control.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

namespace qsil::cli {
namespace {

struct ForestFlags {
  std::string input;
  bool stats = false;
  bool keep_concave = false;
  int threads = 0;
  int min_fit_planes = 15;
};

int run_forest(const ForestFlags& f) {
  namespace fs = std::filesystem;
  const fs::path path(f.input);
  if (!fs::exists(path)) throw Error(f.input + ": no such file");
  std::string ext = path.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  // The forest's inputs as the boundary term builds them (edgetree::forest_inputs): a scene's
  // shapes with their crease sets; a lone mesh is smooth-shaded and one-sided (concave creases).
  std::vector<TriangleMesh> meshes;
  std::vector<std::string> names;
  std::vector<edgetree::ForestShapeInput> in;
  Scene scene;
  if (ext == ".obj") {
    meshes.push_back(load_obj(path));
    names.push_back(path.filename().string());
    edgetree::ForestShapeInput one;
    one.mesh = &meshes[0];
    one.creases = edgetree::CreaseSet::Concave;
    in.push_back(one);
  } else if (ext == ".xml") {
    scene = load_scene(path);
    for (const auto& s : scene.shapes) names.push_back(s.id.empty() ? s.type + " (" + s.source + ")" : s.id);
    in = edgetree::forest_inputs(scene);
  } else {
    throw Error(f.input + ": expected a .obj mesh or a .xml scene");
  }
  std::unique_ptr<tbb::global_control> gc;
  if (f.threads > 0)
    gc = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, size_t(f.threads));
  edgetree::ForestOptions opt;
  opt.edges.keep_concave = f.keep_concave;
  opt.fit.min_fit_planes = f.min_fit_planes;
  const auto t0 = std::chrono::steady_clock::now();
  const edgetree::EdgeForest forest = edgetree::EdgeForest::build(in, opt);
  const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  size_t edges_total = 0;
  for (const auto& st : forest.stats()) {
    using edgetree::EdgeClass;
    auto c = [&](EdgeClass k) { return st.edge_counts[int(k)]; };
    edges_total += st.edges_kept + st.edges_always;
    if (f.stats) {
      std::printf("shape %d (%s)\n", st.shape, names[st.shape].c_str());
      std::printf(
          "  edges: %d total, %d convex, %d concave, %d flat, %d boundary, "
          "%d non-manifold, %d inconsistent\n",
          st.edges_total, c(EdgeClass::Convex), c(EdgeClass::Concave), c(EdgeClass::Flat), c(EdgeClass::Boundary),
          c(EdgeClass::NonManifold), c(EdgeClass::Inconsistent));
      std::printf("  kept in tree: %d, always-candidate: %d (%d creases; always-candidate tree: %d nodes)\n",
                  st.edges_kept, st.edges_always, st.creases, st.always_nodes);
      std::printf("  nodes: %d (%d inner, %d leaves, %d roots), depth %d\n", st.nodes, st.inner_nodes, st.leaves,
                  st.roots, st.depth);
      std::printf(
          "  inner nodes: %d fitted, %d with quadrics, %d unrejectable, %d box-only, %d inherited quadric, "
          "%d LP\n",
          st.fitted, st.quadrics, st.unrejectable, st.box_only, st.inherited, st.used_lp);
      std::printf("  build time: %.4f s\n", st.build_seconds);
    }
  }
  for (const edgetree::CrossingGroup& g : forest.crossing_groups()) {
    edges_total += size_t(g.segments);
    if (f.stats)
      std::printf("intersection curve of shapes %d (%s) and %d (%s): %d segments\n", g.shape0,
                  names[size_t(g.shape0)].c_str(), g.shape1, names[size_t(g.shape1)].c_str(), g.segments);
  }
  const edgetree::IntersectionCurveStats& cs = forest.crossing_stats();
  if (f.stats)
    std::printf("intersection curves: %lld candidate triangle pairs, %lld crossing, %.4f s (BVH build %.4f s)\n",
                cs.candidate_pairs, cs.crossing_pairs, cs.seconds, cs.build_seconds);
  const double bpe = edges_total ? double(forest.memory_bytes()) / double(edges_total) : 0.0;
  std::printf(
      "forest: %zu shapes, %zu edges (%zu intersection-curve segments), %zu nodes, %zu roots, %.4f s, %.1f "
      "bytes/edge\n",
      forest.stats().size(), edges_total, forest.crossings().size(), forest.nodes().size(), forest.roots().size(),
      total, bpe);
  return 0;
}

const CommandRegistrar registrar{
    {"forest", "Build the quadric edge forest of a mesh or scene and print statistics",
     [](CLI::App& app) -> std::function<int()> {
       auto flags = std::make_shared<ForestFlags>();
       app.add_option("input", flags->input, "MESH.obj or SCENE.xml")->required();
       app.add_flag("--stats", flags->stats, "Print per-shape statistics");
       app.add_flag("--keep-concave", flags->keep_concave,
                    "Keep concave edges (needed for open meshes or a camera inside a closed one)");
       app.add_option("--threads", flags->threads, "Worker threads (0 = all)")->check(qsil::cli::non_negative_number());
       app.add_option("--min-fit-planes", flags->min_fit_planes,
                      "Fewer distinct planes: inherit the parent's quadric (default 15)")
           ->check(qsil::cli::positive_number());
       return [flags]() { return run_forest(*flags); };
     }}};

}  // namespace
}  // namespace qsil::cli
