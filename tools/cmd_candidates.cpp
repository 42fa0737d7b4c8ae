/// @file cmd_candidates.cpp
/// `qsil candidates` ([QSS] Sec. 5.1, Fig. 8): for one shading point, every edge each method can
/// sample (non-zero probability), found by exhaustive traversal of its hierarchy.
///
///   qsil candidates SCENE.xml (--pixel X,Y | --point X,Y,Z --normal X,Y,Z)
///                   [--methods quadric,quadric-box,vsphere,vsphere-solid,uniform] [--shapes ID,...]
///                   [--size N] [--out-dir DIR] [--no-grid] [-D name=value]...
///
/// Shading point: the first hit of the ray through the centre of pixel (X,Y) (normal: the hit
/// triangle's geometric normal, turned toward the camera for twosided BSDFs; wo toward the
/// camera), or the given point/normal (wo toward the camera centre). Eligible shapes: every shape
/// (as for a moving shading point, docs/architecture.md §2) or the --shapes list.
/// Per method (quadric and quadric-box: the edge forest, every accepted child down to the
/// leaves, whose edges are tested exactly; vsphere, vsphere-solid: Li's tree with the Hough
/// origin at the camera centre, every accepted child down to the one-edge leaves; uniform: every
/// edge), printed and written to DIR/summary.json and summary.csv:
/// - candidates: edges with probability > 0; silhouettes among them; silhouettes with a point
///   above the shading point's tangent plane ("upper hemisphere");
/// - non-silhouette mass: the total probability of candidates that are not silhouettes;
/// - dead-end mass: 1 - total candidate probability (traversals that end with every child
///   rejected); both are zero-contribution samples.
/// Pictures: DIR/<method>-camera.png (scene camera) and <method>-overview.png (overview_camera):
/// the meshes' wireframe in grey, non-silhouette candidates green, silhouette candidates red, the
/// shading point black with its normal; DIR/<method>-edges.obj: the candidate line sets and the
/// point for external viewers; DIR/grid.png: labelled by tools/candidates_grid.py (matplotlib).

#include "cli_common.h"
#include "cli_wireframe.h"
#include "commands.h"
#include "qsil/edgetree/edge_forest.h"
#include "qsil/edgetree/rejection_test.h"
#include "qsil/edgetree/silhouette_sampler.h"
#include "qsil/edgetree/uniform_sampler.h"
#include "qsil/edgetree/vsphere_sampler.h"
#include "qsil/integrators/boundary_term.h"
#include "qsil/error.h"
#include "qsil/ray_tracer.h"
#include "qsil/scene.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace qsil::cli {
namespace {

using edgetree::EdgeForest;
using edgetree::EdgeProbability;
using edgetree::ForestEdge;
using edgetree::SilhouetteQuery;

struct CandidatesFlags {
  std::string scene;
  std::vector<std::string> defines;
  std::vector<int> pixel;
  std::vector<double> point, normal;
  std::vector<std::string> methods{"quadric", "quadric-box", "vsphere", "vsphere-solid", "uniform"};
  std::vector<std::string> shapes;
  int size = 768;
  std::string out_dir;
  bool no_grid = false;
  std::string scripts_dir;
};

/// Exhaustive traversal of the quadric forest: accepted children down to the leaves, whose
/// silhouette edges get their probability from silhouette_edge_probability. `leaf_edges` counts
/// the leaf edges reached (tested exactly).
std::vector<EdgeProbability> forest_candidates(const EdgeForest& f, const SilhouetteQuery& q, long long& leaf_edges) {
  std::vector<EdgeProbability> out;
  auto eligible = [&](int shape) { return !q.eligible || (*q.eligible)[size_t(shape)]; };
  std::vector<int> stack;
  for (int r : f.roots())
    if (eligible(f.node(r).shape) && edgetree::may_have_silhouette(f, r, q.p, q.mode)) stack.push_back(r);
  for (const ForestEdge& e : f.always_edges())
    if (eligible(e.shape)) out.push_back({&e, edgetree::silhouette_edge_probability(f, q, &e)});
  while (!stack.empty()) {
    const int n = stack.back();
    stack.pop_back();
    if (f.node(n).is_leaf()) {
      for (const ForestEdge& e : f.leaf_edges(n)) {
        ++leaf_edges;
        if (!edgetree::edge_is_silhouette(e, q.p)) continue;
        const double pr = edgetree::silhouette_edge_probability(f, q, &e);
        if (pr > 0) out.push_back({&e, pr});
      }
      continue;
    }
    const edgetree::ForestNode& node = f.node(n);
    for (int c = node.first; c < node.first + node.count; ++c)
      if (edgetree::may_have_silhouette(f, c, q.p, q.mode)) stack.push_back(c);
  }
  return out;
}

struct MethodStats {
  std::string name;
  long long candidates = 0, silhouettes = 0, upper = 0, leaf_edges = -1;
  double non_sil_mass = 0, dead_end_mass = 0, upper_mass = 0;
};

bool upper_hemisphere(const ForestEdge& e, const Vec3& p, const Vec3& n) {
  return std::max((e.p0 - p).dot(n), (e.p1 - p).dot(n)) > 0;
}

void write_text(const std::filesystem::path& p, const std::string& s) {
  const std::filesystem::path tmp = p.string() + ".tmp";
  {
    std::ofstream out(tmp);
    out << s;
    if (!out) throw Error(p.string() + ": cannot write");
  }
  std::filesystem::rename(tmp, p);
}

int run_candidates(const CandidatesFlags& f) {
  namespace fs = std::filesystem;
  std::map<std::string, std::string> defaults;
  for (const auto& d : f.defines) {
    const auto eq = d.find('=');
    if (eq == std::string::npos || eq == 0) throw Error("-D '" + d + "': expected name=value");
    defaults[d.substr(0, eq)] = d.substr(eq + 1);
  }
  const Scene scene = load_scene(f.scene, defaults);
  const RayTracer tracer(scene);
  const Camera& cam = scene.camera;
  // ---- The shading point.
  Vec3 p, n, wo;
  int shape = -1;
  std::string where;
  if (!f.pixel.empty()) {
    if (f.pixel.size() != 2) throw Error("--pixel: expected X,Y");
    const int x = f.pixel[0], y = f.pixel[1];
    if (x < 0 || y < 0 || x >= cam.width || y >= cam.height)
      throw Error("--pixel " + std::to_string(x) + "," + std::to_string(y) + ": outside the " +
                  std::to_string(cam.width) + "x" + std::to_string(cam.height) + " image");
    const Vec3 d = cam.direction(x + 0.5, y + 0.5);
    const Hit h = tracer.intersect(cam.origin(), d);
    if (!h.valid()) throw Error("--pixel " + std::to_string(x) + "," + std::to_string(y) + ": the camera ray hits nothing");
    shape = h.shape;
    p = cam.origin() + h.t * d;
    n = scene.shapes[size_t(shape)].mesh.face_cross(h.triangle).normalized();
    wo = -d;
    where = "pixel " + std::to_string(x) + "," + std::to_string(y);
  } else {
    if (f.point.size() != 3 || f.normal.size() != 3) throw Error("candidates: give --pixel X,Y or --point X,Y,Z --normal X,Y,Z");
    p = Vec3(f.point[0], f.point[1], f.point[2]);
    n = Vec3(f.normal[0], f.normal[1], f.normal[2]);
    if (!(n.norm() > 0)) throw Error("--normal: zero vector");
    n.normalize();
    wo = (cam.origin() - p).normalized();
    where = "point";
  }
  BSDFDesc bsdf;  // a diffuse default for a free point
  if (shape >= 0 && scene.shapes[size_t(shape)].bsdf >= 0) bsdf = scene.bsdfs[size_t(scene.shapes[size_t(shape)].bsdf)];
  if (bsdf.twosided && n.dot(wo) < 0) n = -n;
  SilhouetteQuery q;
  q.p = p;
  q.frame = Frame(n);
  q.ltc = bsdf_ltc(bsdf, q.frame.to_local(wo));
  std::vector<bool> eligible(scene.shapes.size(), f.shapes.empty());
  for (const auto& id : f.shapes) {
    const int s = scene.find_shape(id);
    if (s < 0) throw Error("--shapes: no shape with id '" + id + "'");
    eligible[size_t(s)] = true;
  }
  q.eligible = &eligible;
  // ---- The forest (over every shape, as render_gradient builds it) and the samplers.
  const EdgeForest forest = EdgeForest::build(edgetree::forest_inputs(scene));
  const fs::path dir = f.out_dir.empty() ? fs::path("out") / "candidates" : fs::path(f.out_dir);
  fs::create_directories(dir);
  // Ground truth over the eligible shapes' candidate edges.
  long long truth_sil = 0, truth_upper = 0;
  for (const auto* list : {&forest.edges(), &forest.always_edges()})
    for (const ForestEdge& e : *list)
      if (eligible[size_t(e.shape)] && edgetree::edge_is_silhouette(e, p)) {
        ++truth_sil;
        truth_upper += upper_hemisphere(e, p, n);
      }
  // ---- Views.
  Camera view_cam = cam, view_over = overview_camera(scene);
  for (Camera* c : {&view_cam, &view_over}) {
    const double aspect = double(cam.width) / cam.height;
    c->width = aspect >= 1 ? f.size : std::max(1, int(f.size * aspect));
    c->height = aspect >= 1 ? std::max(1, int(f.size / aspect)) : f.size;
  }
  const Rgb grey{200, 200, 200}, green{0, 160, 0}, red{220, 30, 30}, black{0, 0, 0};
  std::vector<MethodStats> all;
  for (const std::string& m : f.methods) {
    std::vector<EdgeProbability> probs;
    MethodStats st;
    st.name = m;
    if (m == "quadric" || m == "quadric-box") {
      SilhouetteQuery qq = q;
      qq.mode = m == "quadric" ? edgetree::RejectionMode::Quadric : edgetree::RejectionMode::Box;
      st.leaf_edges = 0;
      probs = forest_candidates(forest, qq, st.leaf_edges);
    } else if (m == "vsphere" || m == "vsphere-solid") {
      const edgetree::VSphereEdgeSampler s(forest, cam.origin(),
                                           m == "vsphere" ? edgetree::VSphereTest::Hollow : edgetree::VSphereTest::Solid);
      probs = s.edge_probabilities(q);
    } else if (m == "uniform") {
      probs = edgetree::UniformEdgeSampler(forest).edge_probabilities(q);
    } else {
      throw Error("--methods: unknown method '" + m + "' (quadric, quadric-box, vsphere, vsphere-solid, uniform)");
    }
    double total = 0;
    for (const auto& e : probs) {
      if (!(e.probability > 0)) continue;
      ++st.candidates;
      total += e.probability;
      if (edgetree::edge_is_silhouette(*e.edge, p)) {
        ++st.silhouettes;
        if (upper_hemisphere(*e.edge, p, n)) {
          ++st.upper;
          st.upper_mass += e.probability;
        }
      } else {
        st.non_sil_mass += e.probability;
      }
    }
    st.dead_end_mass = std::max(0.0, 1.0 - total);
    // ---- Pictures and the line set.
    for (int v = 0; v < 2; ++v) {
      WireframeCanvas canvas(v == 0 ? view_cam : view_over, {255, 255, 255});
      for (const Shape& s : scene.shapes)
        for (const auto& t : s.mesh.triangles)
          for (int k = 0; k < 3; ++k)
            canvas.line(s.mesh.positions[size_t(t[k])], s.mesh.positions[size_t(t[(k + 1) % 3])], grey, 1);
      for (int pass = 0; pass < 2; ++pass)  // silhouettes on top
        for (const auto& e : probs) {
          if (!(e.probability > 0)) continue;
          const bool sil = edgetree::edge_is_silhouette(*e.edge, p);
          if (sil != (pass == 1)) continue;
          canvas.line(e.edge->p0, e.edge->p1, sil ? red : green, 2);
        }
      const double len = 0.05 * scene.bounds().diagonal();
      canvas.line(p, p + len * n, black, 2);
      canvas.dot(p, black, 5);
      canvas.write(dir / (m + (v == 0 ? "-camera.png" : "-overview.png")));
    }
    std::ostringstream obj;
    obj << "# qsil candidates: " << m << " at " << where << "\n";
    int vcount = 0;
    for (int pass = 0; pass < 2; ++pass) {
      obj << "o " << (pass == 0 ? "candidates_not_silhouette" : "candidates_silhouette") << "\n";
      for (const auto& e : probs) {
        if (!(e.probability > 0) || edgetree::edge_is_silhouette(*e.edge, p) != (pass == 1)) continue;
        obj << "v " << e.edge->p0.x() << " " << e.edge->p0.y() << " " << e.edge->p0.z() << "\n";
        obj << "v " << e.edge->p1.x() << " " << e.edge->p1.y() << " " << e.edge->p1.z() << "\n";
        obj << "l " << vcount + 1 << " " << vcount + 2 << "\n";
        vcount += 2;
      }
    }
    obj << "o shading_point\nv " << p.x() << " " << p.y() << " " << p.z() << "\np " << vcount + 1 << "\n";
    write_text(dir / (m + "-edges.obj"), obj.str());
    std::printf("candidates %-13s %6lld candidates, %5lld silhouettes (%lld facing the upper hemisphere), "
                "non-silhouette mass %.4f, dead-end mass %.4f%s\n",
                m.c_str(), st.candidates, st.silhouettes, st.upper, st.non_sil_mass, st.dead_end_mass,
                st.leaf_edges >= 0 ? (", leaf edges tested " + std::to_string(st.leaf_edges)).c_str() : "");
    all.push_back(st);
  }
  // ---- Summaries.
  std::ostringstream js, csv;
  js.precision(9);
  csv.precision(9);
  js << "{\n  \"scene\": \"" << portable_path(f.scene) << "\",\n  \"where\": \"" << where << "\",\n  \"shading_point\": [" << p.x()
     << ", " << p.y() << ", " << p.z() << "],\n  \"normal\": [" << n.x() << ", " << n.y() << ", " << n.z()
     << "],\n  \"shape\": \"" << (shape >= 0 ? scene.shapes[size_t(shape)].id : std::string()) << "\",\n"
     << "  \"true_silhouettes\": " << truth_sil << ",\n  \"true_silhouettes_upper\": " << truth_upper
     << ",\n  \"methods\": [\n";
  csv << "method,candidates,silhouettes,upper_silhouettes,non_silhouette_mass,dead_end_mass,upper_silhouette_mass,leaf_edges_tested\n";
  for (size_t i = 0; i < all.size(); ++i) {
    const MethodStats& s = all[i];
    js << "    {\"method\": \"" << s.name << "\", \"candidates\": " << s.candidates << ", \"silhouettes\": " << s.silhouettes
       << ", \"upper_silhouettes\": " << s.upper << ", \"non_silhouette_mass\": " << s.non_sil_mass
       << ", \"dead_end_mass\": " << s.dead_end_mass << ", \"upper_silhouette_mass\": " << s.upper_mass
       << ", \"leaf_edges_tested\": " << s.leaf_edges << ", \"images\": [\"" << s.name << "-camera.png\", \"" << s.name
       << "-overview.png\"]}" << (i + 1 < all.size() ? "," : "") << "\n";
    csv << s.name << "," << s.candidates << "," << s.silhouettes << "," << s.upper << "," << s.non_sil_mass << ","
        << s.dead_end_mass << "," << s.upper_mass << "," << s.leaf_edges << "\n";
  }
  js << "  ]\n}\n";
  write_text(dir / "summary.json", js.str());
  write_text(dir / "summary.csv", csv.str());
  if (!f.no_grid) {
    if (run_python_script("candidates", "candidates_grid.py", {(dir / "summary.json").string(), (dir / "grid.png").string()},
                          f.scripts_dir) != 0)
      std::fprintf(stderr, "candidates: warning: the grid image was not drawn\n");
  }
  std::printf("candidates: %s at %s, p = (%.4f, %.4f, %.4f), %lld true silhouettes (%lld upper) -> %s\n",
              f.scene.c_str(), where.c_str(), p.x(), p.y(), p.z(), truth_sil, truth_upper, dir.string().c_str());
  return 0;
}

const CommandRegistrar registrar{{"candidates", "Edges each method can sample from one shading point ([QSS] Fig. 8)",
  [](CLI::App& app) -> std::function<int()> {
    auto f = std::make_shared<CandidatesFlags>();
    app.add_option("scene", f->scene, "Scene (.xml)")->required();
    app.add_option("-D", f->defines, "Override a scene <default>: name=value (repeatable)")->allow_extra_args(false);
    app.add_option("--pixel", f->pixel, "Pixel X,Y whose first hit is the shading point")->delimiter(',')->expected(2);
    app.add_option("--point", f->point, "Shading point X,Y,Z (with --normal)")->delimiter(',')->expected(3);
    app.add_option("--normal", f->normal, "Shading normal X,Y,Z (with --point)")->delimiter(',')->expected(3);
    app.add_option("--methods", f->methods, "Methods, comma separated")->delimiter(',');
    app.add_option("--shapes", f->shapes, "Eligible shape ids, comma separated (default: every shape)")->delimiter(',');
    app.add_option("--size", f->size, "Larger side of the pictures in pixels")->capture_default_str();
    app.add_option("--out-dir", f->out_dir, "Output directory (default out/candidates)");
    app.add_flag("--no-grid", f->no_grid, "Skip the labelled grid image (no Python)");
    add_scripts_dir_option(app, f->scripts_dir);
    return [f] { return run_candidates(*f); };
  }}};

}  // namespace
}  // namespace qsil::cli
