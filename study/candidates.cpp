/// @file candidates.cpp
/// The candidate-edge study; see qsil/study/candidates.h.

#include "qsil/study/candidates.h"

#include "qsil/edgetree/edge_forest.h"
#include "qsil/edgetree/node_rejection.h"
#include "qsil/edgetree/silhouette_sampler.h"
#include "qsil/edgetree/uniform_sampler.h"
#include "qsil/edgetree/vsphere_sampler.h"
#include "qsil/error.h"
#include "qsil/files.h"
#include "qsil/edgetree/bsdf_ltc.h"
#include "qsil/integrators/boundary_term.h"
#include "qsil/ray_tracer.h"
#include "qsil/wireframe.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <sstream>

namespace qsil {

namespace {

using edgetree::EdgeForest;
using edgetree::EdgeProbability;
using edgetree::Edge;
using edgetree::SilhouetteQuery;

/// Exhaustive traversal of the quadric forest with the test of `method`: accepted children down
/// to the leaves, whose silhouette edges get their probability from silhouette_edge_probability.
/// `leaf_edges` counts the leaf edges reached (tested exactly).
std::vector<EdgeProbability> forest_candidates(const EdgeForest& f, const SilhouetteQuery& q, Method method,
                                               long long& leaf_edges) {
  std::vector<EdgeProbability> out;
  std::vector<int> stack;
  for (int r : f.roots())
    if (q.is_eligible(f.node(r).shape) && edgetree::may_have_silhouette(f, r, q.p, node_test(method))) stack.push_back(r);
  for (const Edge& e : f.always_edges())
    if (q.is_eligible(e.shape)) out.push_back({&e, edgetree::silhouette_edge_probability(f, q, &e, node_test(method))});
  while (!stack.empty()) {
    const int n = stack.back();
    stack.pop_back();
    if (f.node(n).is_leaf()) {
      for (const Edge& e : f.leaf_edges(n)) {
        ++leaf_edges;
        if (!edgetree::edge_is_silhouette(e, q.p)) continue;
        const double pr = edgetree::silhouette_edge_probability(f, q, &e, node_test(method));
        if (pr > 0) out.push_back({&e, pr});
      }
      continue;
    }
    const edgetree::ForestNode& node = f.node(n);
    for (int c = node.first; c < node.first + node.count; ++c)
      if (edgetree::may_have_silhouette(f, c, q.p, node_test(method))) stack.push_back(c);
  }
  return out;
}

bool upper_hemisphere(const Edge& e, const Vec3& p, const Vec3& n) {
  return std::max((e.p0 - p).dot(n), (e.p1 - p).dot(n)) > 0;
}

Vec3 vec3_of(const std::vector<double>& v) { return Vec3(v[0], v[1], v[2]); }

/// The shading point, its normal and the BSDF's query (see the header).
SilhouetteQuery shading_point(const Scene& scene, const CandidatesOptions& o, CandidatesReport& rep) {
  const Camera& cam = scene.camera;
  Vec3 wo;
  if (!o.pixel.empty()) {
    if (o.pixel.size() != 2) throw Error("--pixel: expected X,Y");
    const int x = o.pixel[0], y = o.pixel[1];
    const std::string at = std::to_string(x) + "," + std::to_string(y);
    if (x < 0 || y < 0 || x >= cam.width || y >= cam.height)
      throw Error("--pixel " + at + ": outside the " + std::to_string(cam.width) + "x" + std::to_string(cam.height) +
                  " image");
    const RayTracer tracer(scene);
    const Vec3 d = cam.direction(x + 0.5, y + 0.5);
    const Hit h = tracer.intersect(cam.origin(), d);
    if (!h.valid()) throw Error("--pixel " + at + ": the camera ray hits nothing");
    rep.shape = h.shape;
    rep.p = cam.origin() + h.t * d;
    rep.n = scene.shapes[size_t(h.shape)].mesh.face_cross(h.triangle).normalized();
    wo = -d;
    rep.where = "pixel " + at;
  } else {
    if (o.point.size() != 3 || o.normal.size() != 3)
      throw Error("candidates: give --pixel X,Y or --point X,Y,Z --normal X,Y,Z");
    rep.p = vec3_of(o.point);
    rep.n = vec3_of(o.normal);
    if (!(rep.n.norm() > 0)) throw Error("--normal: zero vector");
    rep.n.normalize();
    wo = (cam.origin() - rep.p).normalized();
    rep.where = "point";
  }
  BSDFDesc bsdf;  // a diffuse default for a free point
  if (rep.shape >= 0 && scene.shapes[size_t(rep.shape)].bsdf >= 0)
    bsdf = scene.bsdfs[size_t(scene.shapes[size_t(rep.shape)].bsdf)];
  if (bsdf.twosided && rep.n.dot(wo) < 0) rep.n = -rep.n;
  SilhouetteQuery q;
  q.p = rep.p;
  q.frame = Frame(rep.n);
  q.ltc = edgetree::bsdf_ltc(bsdf, q.frame.to_local(wo));
  return q;
}

/// The statistics of one method's candidates.
void summarize(MethodCandidates& m, const Vec3& p, const Vec3& n) {
  double total = 0;
  for (const auto& e : m.edges) {
    ++m.candidates;
    total += e.probability;
    if (edgetree::edge_is_silhouette(*e.edge, p)) {
      ++m.silhouettes;
      if (upper_hemisphere(*e.edge, p, n)) {
        ++m.upper;
        m.upper_mass += e.probability;
      }
    } else {
      m.non_silhouette_mass += e.probability;
    }
  }
  m.dead_end_mass = std::max(0.0, 1.0 - total);
}

}  // namespace

CandidatesReport find_candidates(const Scene& scene, const CandidatesOptions& o) {
  CandidatesReport rep;
  SilhouetteQuery q = shading_point(scene, o, rep);
  auto eligible = std::make_shared<std::vector<bool>>(scene.shapes.size(), o.shapes.empty());
  for (const auto& id : o.shapes) {
    const int s = scene.find_shape(id);
    if (s < 0) throw Error("--shapes: no shape with id '" + id + "'");
    (*eligible)[size_t(s)] = true;
  }
  q.eligible = eligible.get();
  // ---- One forest over every shape (as the gradient estimator builds it): the quadric methods
  // traverse it, the baselines use its edges (an edge forest is an edge set).
  auto forest = std::make_shared<EdgeForest>(EdgeForest::build(edgetree::forest_inputs(scene)));
  rep.keep_alive = std::make_shared<std::pair<decltype(forest), decltype(eligible)>>(forest, eligible);
  for (const auto* list : {&forest->edges(), &forest->always_edges()})
    for (const Edge& e : *list)
      if (q.is_eligible(e.shape) && edgetree::edge_is_silhouette(e, rep.p)) {
        ++rep.true_silhouettes;
        rep.true_upper += upper_hemisphere(e, rep.p, rep.n);
      }
  for (Method m : o.methods) {
    MethodCandidates mc;
    mc.method = m;
    if (uses_edge_forest(m)) {
      mc.leaf_edges = 0;
      mc.edges = forest_candidates(*forest, q, m, mc.leaf_edges);
    } else if (m == Method::VSphere || m == Method::VSphereSolid) {
      mc.edges = edgetree::VSphereEdgeSampler(*forest, scene.camera.origin(), vsphere_test(m)).edge_probabilities(q);
    } else if (m == Method::Uniform) {
      mc.edges = edgetree::UniformEdgeSampler(*forest).edge_probabilities(q);
    } else {
      throw Error("--methods: '" + std::string(method_name(m)) +
                  "' samples no edges (supported: " + method_list(kEdgeSamplingMethods) + ")");
    }
    std::erase_if(mc.edges, [](const EdgeProbability& e) { return !(e.probability > 0); });
    summarize(mc, rep.p, rep.n);
    rep.methods.push_back(std::move(mc));
  }
  return rep;
}

namespace {

/// The two pictures of one method: the scene camera's view and the overview.
void draw_method(const Scene& scene, const CandidatesReport& rep, const MethodCandidates& mc,
                 const std::filesystem::path& dir, int size) {
  const Camera& cam = scene.camera;
  Camera views[2] = {cam, overview_camera(scene)};
  const Rgb grey{200, 200, 200}, green{0, 160, 0}, red{220, 30, 30}, black{0, 0, 0};
  const std::string name(method_name(mc.method));
  for (int v = 0; v < 2; ++v) {
    Camera& c = views[v];
    const double aspect = double(cam.width) / cam.height;
    c.width = aspect >= 1 ? size : std::max(1, int(size * aspect));
    c.height = aspect >= 1 ? std::max(1, int(size / aspect)) : size;
    WireframeCanvas canvas(c, {255, 255, 255});
    for (const Shape& s : scene.shapes)
      for (const auto& t : s.mesh.triangles)
        for (int k = 0; k < 3; ++k)
          canvas.line(s.mesh.positions[size_t(t[k])], s.mesh.positions[size_t(t[(k + 1) % 3])], grey, 1);
    for (int pass = 0; pass < 2; ++pass)  // silhouettes on top
      for (const auto& e : mc.edges) {
        const bool sil = edgetree::edge_is_silhouette(*e.edge, rep.p);
        if (sil == (pass == 1)) canvas.line(e.edge->p0, e.edge->p1, sil ? red : green, 2);
      }
    const double len = 0.05 * scene.bounds().diagonal();
    canvas.line(rep.p, rep.p + len * rep.n, black, 2);
    canvas.dot(rep.p, black, 5);
    canvas.write(dir / (name + (v == 0 ? "-camera.png" : "-overview.png")));
  }
}

/// The candidate line sets and the shading point as OBJ.
std::string edges_obj(const CandidatesReport& rep, const MethodCandidates& mc) {
  std::ostringstream obj;
  obj << "# qsil candidates: " << method_name(mc.method) << " at " << rep.where << "\n";
  int vcount = 0;
  for (int pass = 0; pass < 2; ++pass) {
    obj << "o " << (pass == 0 ? "candidates_not_silhouette" : "candidates_silhouette") << "\n";
    for (const auto& e : mc.edges) {
      if (edgetree::edge_is_silhouette(*e.edge, rep.p) != (pass == 1)) continue;
      obj << "v " << e.edge->p0.x() << " " << e.edge->p0.y() << " " << e.edge->p0.z() << "\n";
      obj << "v " << e.edge->p1.x() << " " << e.edge->p1.y() << " " << e.edge->p1.z() << "\n";
      obj << "l " << vcount + 1 << " " << vcount + 2 << "\n";
      vcount += 2;
    }
  }
  obj << "o shading_point\nv " << rep.p.x() << " " << rep.p.y() << " " << rep.p.z() << "\np " << vcount + 1 << "\n";
  return obj.str();
}

void write_summaries(const Scene& scene, const CandidatesReport& rep, const std::string& scene_path,
                     const std::filesystem::path& dir) {
  nlohmann::ordered_json j = {{"scene", portable_path(scene_path)},
                              {"where", rep.where},
                              {"shading_point", {rep.p.x(), rep.p.y(), rep.p.z()}},
                              {"normal", {rep.n.x(), rep.n.y(), rep.n.z()}},
                              {"shape", rep.shape >= 0 ? scene.shapes[size_t(rep.shape)].id : std::string()},
                              {"true_silhouettes", rep.true_silhouettes},
                              {"true_silhouettes_upper", rep.true_upper},
                              {"methods", nlohmann::ordered_json::array()}};
  std::ostringstream csv;
  csv.precision(9);
  csv << "method,candidates,silhouettes,upper_silhouettes,non_silhouette_mass,dead_end_mass,upper_silhouette_mass,"
         "leaf_edges_tested\n";
  for (const MethodCandidates& m : rep.methods) {
    const std::string name(method_name(m.method));
    j["methods"].push_back({{"method", name},
                            {"candidates", m.candidates},
                            {"silhouettes", m.silhouettes},
                            {"upper_silhouettes", m.upper},
                            {"non_silhouette_mass", m.non_silhouette_mass},
                            {"dead_end_mass", m.dead_end_mass},
                            {"upper_silhouette_mass", m.upper_mass},
                            {"leaf_edges_tested", m.leaf_edges},
                            {"images", {name + "-camera.png", name + "-overview.png"}}});
    csv << name << "," << m.candidates << "," << m.silhouettes << "," << m.upper << "," << m.non_silhouette_mass << ","
        << m.dead_end_mass << "," << m.upper_mass << "," << m.leaf_edges << "\n";
  }
  write_file(dir / "summary.json", j.dump(2) + "\n");
  write_file(dir / "summary.csv", csv.str());
}

}  // namespace

void write_candidates(const Scene& scene, const CandidatesReport& report, const std::string& scene_path,
                      const std::filesystem::path& dir, int size) {
  std::filesystem::create_directories(dir);
  for (const MethodCandidates& mc : report.methods) {
    draw_method(scene, report, mc, dir, size);
    write_file(dir / (std::string(method_name(mc.method)) + "-edges.obj"), edges_obj(report, mc));
  }
  write_summaries(scene, report, scene_path, dir);
}

}  // namespace qsil
