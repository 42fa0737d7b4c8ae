/// @file slice_study.cpp
/// See qsil/study/slice_study.h.

#include "qsil/study/slice_study.h"

#include "qsil/edgetree/edge_forest.h"
#include "qsil/error.h"
#include "qsil/files.h"
#include "qsil/image.h"

#include <tbb/parallel_for.h>
#include <nlohmann/json.hpp>

#include <sstream>

namespace qsil::study {

using namespace qsil::edgetree;

namespace {

/// Colours of the slice images (sRGB).
constexpr std::array<unsigned char, 3> kCorrectReject{225, 225, 225};  // no silhouette, rejected
constexpr std::array<unsigned char, 3> kCorrectAccept{60, 110, 190};   // silhouette, accepted
constexpr std::array<unsigned char, 3> kFalseAccept{245, 150, 30};     // no silhouette, accepted
constexpr std::array<unsigned char, 3> kFalseReject{230, 0, 230};      // silhouette, rejected (bug)

Vec3 vec3_of(const std::vector<double>& v, const char* flag) {
  if (v.size() != 3) throw Error(std::string(flag) + ": expected X,Y,Z");
  return Vec3(v[0], v[1], v[2]);
}

/// The node under study and its default planes.
struct Node {
  TriangleMesh mesh;
  EdgeForest forest;
  Vec3 center = Vec3::Zero();
  std::array<double, 2> heights{};
  double extent = 0;
};

Node make_node(const SliceStudyOptions& o, std::string& label) {
  Node n;
  if (!o.patch.empty()) {
    if (!o.mesh.empty()) throw Error("slices: give either MESH.obj --node ID or --patch, not both");
    const PatchKind kind = parse_patch_kind(o.patch);
    n.mesh = make_canonical_patch(kind);
    label = o.patch;
    n.extent = 4.0;
    if (kind == PatchKind::Sphere) {
      n.heights = {0.9, 2.0};  // through the cap (inside: no silhouette) and above it
    } else {
      n.center = Vec3(0.7, 0.7, 0);
      n.heights = {1.5, 2.5};  // above the patch: regions without silhouettes exist
    }
    return n;
  }
  if (o.mesh.empty()) throw Error("slices: give MESH.obj --node ID or --patch sphere|torus");
  if (o.node < 0) throw Error("slices: --node ID is required with a mesh");
  n.mesh = load_obj(o.mesh);
  const ForestShapeInput in{&n.mesh, 0};
  n.forest = EdgeForest::build(std::span(&in, 1));
  if (o.node >= int(n.forest.nodes().size()) || n.forest.node(o.node).is_leaf())
    throw Error("--node " + std::to_string(o.node) + ": not an inner node (the forest has " +
                std::to_string(n.forest.nodes().size()) + " nodes)");
  label = std::filesystem::path(o.mesh).stem().string() + "-node" + std::to_string(o.node);
  const Box3& b = n.forest.node(o.node).bp;
  n.center = b.center();
  n.heights = {b.hi.z() + 0.1 * b.diagonal(), b.hi.z() + 0.5 * b.diagonal()};
  n.extent = 3.0 * b.diagonal();
  return n;
}

/// Evaluates one plane: verdicts at resolution^2 points, counts and pictures.
PlaneStats evaluate_plane(const PatchTests& tests, const Vec3& c, const Vec3& normal, double extent, int N) {
  const Frame plane_frame(normal);
  std::vector<SliceVerdict> v(size_t(N) * N);
  tbb::parallel_for(0, N, [&](int y) {
    for (int x = 0; x < N; ++x) {
      const Vec3 p =
          c + ((x + 0.5) / N - 0.5) * extent * plane_frame.s + (0.5 - (y + 0.5) / N) * extent * plane_frame.t;
      v[size_t(y) * N + x] = tests.evaluate(p);
    }
  });
  PlaneStats st;
  for (size_t t = 0; t < kRejectionMethods.size(); ++t) {
    std::vector<unsigned char>& rgb = st.images[t];
    rgb.resize(size_t(N) * N * 3);
    for (size_t i = 0; i < v.size(); ++i) {
      const bool truth = v[i].truth, acc = v[i].accept[t];
      const auto& col = truth ? (acc ? kCorrectAccept : kFalseReject) : (acc ? kFalseAccept : kCorrectReject);
      for (int ch = 0; ch < 3; ++ch) rgb[3 * i + size_t(ch)] = col[size_t(ch)];
      st.false_accepts[t] += !truth && acc;
      st.false_rejects[t] += truth && !acc;
      st.accepts[t] += acc;
    }
  }
  st.points = (long long)v.size();
  for (const auto& x : v) st.no_silhouette += !x.truth;
  return st;
}

double rate(long long a, long long b) { return b > 0 ? double(a) / double(b) : 0.0; }

}  // namespace

long long SliceStudy::false_rejects() const {
  long long n = 0;
  for (const PlaneStats& p : planes)
    for (long long f : p.false_rejects) n += f;
  return n;
}

SliceStudy run_slice_study(const SliceStudyOptions& o) {
  SliceStudy s;
  Node node = make_node(o, s.label);
  if (!o.center.empty()) node.center = vec3_of(o.center, "--center");
  if (!o.normal.empty()) s.normal = vec3_of(o.normal, "--plane-normal");
  if (!(s.normal.norm() > 0)) throw Error("--plane-normal: zero vector");
  s.normal.normalize();
  if (!o.heights.empty()) {
    if (o.heights.size() != 2) throw Error("--heights: expected H1,H2");
    node.heights = {o.heights[0], o.heights[1]};
  }
  s.extent = o.extent > 0 ? o.extent : node.extent;
  if (o.resolution < 2 || o.resolution > 4096) throw Error("--resolution: expected 2..4096");
  s.resolution = o.resolution;
  s.origin = o.origin.empty() ? PatchTests::default_origin(node.mesh) : vec3_of(o.origin, "--origin");
  const PatchTests tests = o.patch.empty() ? PatchTests::from_forest_node(node.forest, o.node, s.origin)
                                           : PatchTests::from_mesh(node.mesh, s.origin);
  s.edges = tests.num_edges();
  s.origin_silhouettes = tests.origin_silhouettes();
  for (int k = 0; k < 2; ++k) {
    const double h = node.heights[size_t(k)];
    const Vec3 c = node.center - (s.normal.dot(node.center) - h) * s.normal;
    s.planes[size_t(k)] = evaluate_plane(tests, c, s.normal, s.extent, s.resolution);
    s.planes[size_t(k)].height = h;
  }
  return s;
}

void write_slice_study(const SliceStudy& s, const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  nlohmann::ordered_json j = {{"node", s.label},
                              {"edges", s.edges},
                              {"hough_origin", {s.origin.x(), s.origin.y(), s.origin.z()}},
                              {"origin_silhouettes", s.origin_silhouettes},
                              {"plane_normal", {s.normal.x(), s.normal.y(), s.normal.z()}},
                              {"extent", s.extent},
                              {"resolution", s.resolution},
                              {"planes", nlohmann::ordered_json::array()},
                              {"false_rejects", s.false_rejects()}};
  std::ostringstream csv;
  csv.precision(9);
  csv << "plane,height,test,points,no_silhouette,false_accepts,false_accept_rate,false_rejects\n";
  for (int k = 0; k < 2; ++k) {
    const PlaneStats& st = s.planes[size_t(k)];
    nlohmann::ordered_json plane = {{"plane", k + 1},
                                    {"height", st.height},
                                    {"points", st.points},
                                    {"no_silhouette", st.no_silhouette},
                                    {"tests", nlohmann::ordered_json::object()}};
    for (size_t t = 0; t < kRejectionMethods.size(); ++t) {
      const std::string name(method_name(kRejectionMethods[t]));
      const std::string image = name + "-plane" + std::to_string(k + 1) + ".png";
      write_png(dir / image, s.resolution, s.resolution, st.images[t]);
      plane["tests"][name] = {{"false_accepts", st.false_accepts[t]},
                              {"false_accept_rate", rate(st.false_accepts[t], st.no_silhouette)},
                              {"false_rejects", st.false_rejects[t]},
                              {"image", image}};
      csv << k + 1 << "," << st.height << "," << name << "," << st.points << "," << st.no_silhouette << ","
          << st.false_accepts[t] << "," << rate(st.false_accepts[t], st.no_silhouette) << "," << st.false_rejects[t]
          << "\n";
    }
    j["planes"].push_back(plane);
  }
  write_file(dir / "summary.json", j.dump(2) + "\n");
  write_file(dir / "summary.csv", csv.str());
}

}  // namespace qsil::study
