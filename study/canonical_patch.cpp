/// @file canonical_patch.cpp
/// See canonical_patch.h.

#include "qsil/study/canonical_patch.h"

#include "qsil/check.h"
#include "qsil/edgetree/mesh_edges.h"
#include "qsil/edgetree/node_rejection.h"
#include "qsil/error.h"

#include <cmath>
#include <set>

namespace qsil::study {

using namespace qsil::edgetree;

PatchKind parse_patch_kind(const std::string& name) {
  if (name == "sphere") return PatchKind::Sphere;
  if (name == "torus") return PatchKind::Torus;
  throw Error("--patch '" + name + "': unsupported (supported: sphere, torus)");
}

bool SliceVerdict::accepts(Method method) const {
  for (size_t i = 0; i < kRejectionMethods.size(); ++i)
    if (kRejectionMethods[i] == method) return accept[i];
  QSIL_CHECK_MSG(false, "no rejection test for method " << method_name(method));
  return false;  // not reached
}

namespace {

/// Adds triangle (a, b, c) wound so that its normal points away from `inside`.
void add_outward(TriangleMesh& m, int a, int b, int c, const Vec3& inside) {
  const Vec3 n =
      (m.positions[size_t(b)] - m.positions[size_t(a)]).cross(m.positions[size_t(c)] - m.positions[size_t(a)]);
  const Vec3 centroid = (m.positions[size_t(a)] + m.positions[size_t(b)] + m.positions[size_t(c)]) / 3.0;
  if (n.dot(centroid - inside) >= 0)
    m.triangles.emplace_back(a, b, c);
  else
    m.triangles.emplace_back(a, c, b);
}

}  // namespace

TriangleMesh make_canonical_patch(PatchKind kind) {
  TriangleMesh m;
  if (kind == PatchKind::Sphere) {
    constexpr int rings = 12, sectors = 16;
    const double theta_max = 50.0 * kPi / 180.0;
    m.positions.emplace_back(0, 0, 1);
    for (int i = 1; i <= rings; ++i) {
      const double th = theta_max * i / rings;
      for (int j = 0; j < sectors; ++j) {
        const double ph = 2 * kPi * j / sectors;
        m.positions.emplace_back(std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th));
      }
    }
    auto v = [&](int i, int j) { return 1 + (i - 1) * sectors + (j % sectors); };
    const Vec3 c = Vec3::Zero();
    for (int j = 0; j < sectors; ++j) add_outward(m, 0, v(1, j), v(1, j + 1), c);
    for (int i = 1; i < rings; ++i)
      for (int j = 0; j < sectors; ++j) {
        add_outward(m, v(i, j), v(i + 1, j), v(i + 1, j + 1), c);
        add_outward(m, v(i, j), v(i + 1, j + 1), v(i, j + 1), c);
      }
  } else {
    constexpr int nu = 16, nv = 12;
    constexpr double R = 1.0, r = 0.4;
    const double v0 = 30.0 * kPi / 180.0, v1 = 150.0 * kPi / 180.0;
    for (int i = 0; i <= nu; ++i)
      for (int j = 0; j <= nv; ++j) {
        const double u = 0.5 * kPi * i / nu, v = v0 + (v1 - v0) * j / nv;
        m.positions.emplace_back((R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u),
                                 r * std::sin(v));
      }
    auto id = [&](int i, int j) { return i * (nv + 1) + j; };
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nv; ++j) {
        // The tube centre of the quad is the inside reference of its two triangles.
        const double u = 0.5 * kPi * (i + 0.5) / nu;
        const Vec3 c(R * std::cos(u), R * std::sin(u), 0);
        add_outward(m, id(i, j), id(i + 1, j), id(i + 1, j + 1), c);
        add_outward(m, id(i, j), id(i + 1, j + 1), id(i, j + 1), c);
      }
  }
  m.normals = vertex_normals(m);
  return m;
}

Vec3 PatchTests::default_origin(const TriangleMesh& mesh) {
  Vec3 n = Vec3::Zero();
  for (int f = 0; f < mesh.num_triangles(); ++f) n += mesh.face_cross(f);
  const Box3 b = mesh.bounds();
  if (!(n.norm() > 0)) n = Vec3(0, 0, 1);
  return b.center() + 3.0 * b.diagonal() * n.normalized();
}

PatchTests PatchTests::from_mesh(const TriangleMesh& mesh, const Vec3& o) {
  PatchTests t;
  t.o_ = o;
  EdgeOptions eo;
  eo.keep_concave = true;
  const MeshEdgeSet es = build_mesh_edges(mesh, 0, eo);
  std::set<int> faces;
  for (int k : es.kept) {
    const MeshEdge& e = es.edges[size_t(k)];
    t.wedges_.push_back({e.q0, e.q1});
    faces.insert(e.f0);
    faces.insert(e.f1);
    t.bp_.expand(mesh.positions[size_t(e.v0)]);
    t.bp_.expand(mesh.positions[size_t(e.v1)]);
  }
  std::vector<Vec4> planes;
  for (int f : faces) planes.push_back(es.face_planes[size_t(f)]);
  const NodeFit fit = fit_node(planes, t.wedges_, t.bp_, nullptr);
  t.flags_ = fit.flags;
  t.bound_ = fit.bound;
  for (const Wedge& w : t.wedges_) {
    const Vec4 x(o.x(), o.y(), o.z(), 1.0);
    if (w.q0.dot(x) * w.q1.dot(x) <= 0) {
      ++t.origin_sil_;
      continue;
    }
    t.bh_.expand(hough_point(w.q0, o));
    t.bh_.expand(hough_point(w.q1, o));
  }
  return t;
}

PatchTests PatchTests::from_forest_node(const EdgeForest& forest, int node, const Vec3& o) {
  PatchTests t;
  t.o_ = o;
  t.forest_ = &forest;
  t.node_ = node;
  const ForestNode& n = forest.node(node);
  t.flags_ = n.flags;
  t.bp_ = n.bp;
  for (int i = n.edge_begin; i < n.edge_end; ++i) {
    const Edge& e = forest.edges()[size_t(i)];
    t.wedges_.push_back({e.q0, e.q1});
    if (edge_is_silhouette(e, o)) {
      ++t.origin_sil_;
      continue;
    }
    t.bh_.expand(hough_point(e.q0, o));
    t.bh_.expand(hough_point(e.q1, o));
  }
  return t;
}

SliceVerdict PatchTests::evaluate(const Vec3& p) const {
  SliceVerdict v;
  const Vec4 x(p.x(), p.y(), p.z(), 1.0);
  for (const Wedge& w : wedges_) {
    const double g0 = w.q0.dot(x), g1 = w.q1.dot(x);
    if (g0 * g1 <= 0.0) {
      v.truth = true;
      break;
    }
  }
  for (size_t i = 0; i < kRejectionMethods.size(); ++i) {
    const Method m = kRejectionMethods[i];
    if (uses_edge_forest(m)) {
      if (forest_) {
        v.accept[i] = may_have_silhouette(*forest_, node_, p, node_test(m));
      } else {
        const bool box_only = m == Method::QuadricBox || (flags_ & kNodeBoxOnly);
        v.accept[i] = (flags_ & kNodeUnrejectable) || bound_may_have_silhouette(bound_, box_only, p);
      }
    } else {
      v.accept[i] = origin_sil_ > 0 || vsphere_box_may_have_silhouette(bh_, bp_.max_abs(), p, o_, vsphere_test(m));
    }
  }
  return v;
}

}  // namespace qsil::study
