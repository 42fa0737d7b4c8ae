/// @file regularized_visibility.cpp
/// See qsil/integrators/regularized_visibility.h.

#include "qsil/integrators/regularized_visibility.h"

#include "qsil/error.h"

#include <array>
#include <map>
#include <utility>
#include <string>

namespace qsil {

Regularization Regularization::for_scene(const Scene& scene, double width_rel) {
  if (!(width_rel > 0) || !std::isfinite(width_rel))
    throw Error("regularized: width must be positive and finite (got " + std::to_string(width_rel) + ")");
  const double diag = scene.bounds().diagonal();
  if (!(diag > 0) || !std::isfinite(diag)) throw Error("regularized: the scene has no extent to scale the width by");
  Regularization r;
  r.width = width_rel * diag;
  return r;
}

SoftScene::SoftScene(const Scene& scene, const Regularization& reg) : reg_(reg), query_(scene, reg.reach()) {
  boundary_.resize(scene.shapes.size());
  for (size_t s = 0; s < scene.shapes.size(); ++s) {
    const auto& tris = scene.shapes[s].mesh.triangles;
    std::map<std::pair<int, int>, int> count;  // undirected mesh edge -> triangles that hold it
    for (const Eigen::Vector3i& t : tris)
      for (int i = 0; i < 3; ++i) ++count[std::minmax(t[i], t[(i + 1) % 3])];
    boundary_[s].resize(tris.size());
    for (size_t f = 0; f < tris.size(); ++f) {
      uint8_t mask = 0;
      for (int i = 0; i < 3; ++i)
        if (count[std::minmax(tris[f][i], tris[f][(i + 1) % 3])] == 1) mask |= uint8_t(1u << i);
      boundary_[s][f] = mask;
    }
  }
}

double soft_ray_tmin(double scale, const Vec3& p, const Vec3& local_origin) {
  return kRayOffsetRelative * std::max(scale, (p - local_origin).cwiseAbs().maxCoeff());
}

void find_soft_candidates(const Scene& scene, const RayTracer* tracer, const SoftScene& soft, const Vec3& o,
                          const Vec3& d, double tmin, double tmax, int skip_shape, int skip_triangle, SoftRay& out) {
  const Regularization& reg = soft.regularization();
  out.candidates.clear();
  // Möller-Trumbore as make_interaction, in double: t and the barycentrics on the plane.
  struct Crossing {
    double t = 0, b1 = 0, b2 = 0;
    bool valid = false;
  };
  const auto cross = [&](const Vec3& v0, const Vec3& v1, const Vec3& v2) {
    Crossing c;
    const Vec3 e1 = v1 - v0, e2 = v2 - v0;
    const Vec3 pvec = d.cross(e2);
    const double det = e1.dot(pvec);
    if (!(det != 0) || !std::isfinite(det)) return c;  // the ray runs in the plane
    const double inv = 1.0 / det;
    const Vec3 tvec = o - v0;
    const Vec3 qvec = tvec.cross(e1);
    c.t = e2.dot(qvec) * inv;
    c.b1 = tvec.dot(pvec) * inv;
    c.b2 = d.dot(qvec) * inv;
    c.valid = std::isfinite(c.t);
    return c;
  };
  const auto vertices = [&](int shape, int triangle) {
    const TriangleMesh& mesh = scene.shapes[size_t(shape)].mesh;
    const Eigen::Vector3i& tri = mesh.triangles[size_t(triangle)];
    return std::array<const Vec3*, 3>{&mesh.positions[size_t(tri[0])], &mesh.positions[size_t(tri[1])],
                                      &mesh.positions[size_t(tri[2])]};
  };
  // Nothing behind a triangle crossed inside is seen: Embree's first hit, confirmed in double
  // (crossed inside beyond tmin), bounds the search exactly.
  if (tracer) {
    IgnoreSet ignore;
    ignore.prims[0] = {skip_shape, skip_triangle};
    const Hit h = tracer->intersect(o, d, tmax, ignore);
    if (h.valid()) {
      const auto v = vertices(h.shape, h.triangle);
      const Crossing c = cross(*v[0], *v[1], *v[2]);
      if (c.valid && c.t > tmin && c.b1 >= 0 && c.b2 >= 0 && 1.0 - c.b1 - c.b2 >= 0)
        tmax = std::min(tmax, c.t * (1.0 + 0x1p-20));
    }
  }
  const double inv_w2 = 1.0 / (reg.width * reg.width);
  soft.query().for_each(o, d, tmax, [&](int shape, int triangle) {
    if (shape == skip_shape && triangle == skip_triangle) return;
    const auto v = vertices(shape, triangle);
    const Crossing c = cross(*v[0], *v[1], *v[2]);
    if (!c.valid || !(c.t > tmin) || !(c.t < tmax)) return;
    const double t = c.t;
    const double cos = (*v[1] - *v[0]).cross(*v[2] - *v[0]).normalized().dot(d);
    const unsigned edges = cos < 0 ? 7u : soft.boundary_edges(shape, triangle);  // a back: its mesh's edges only
    const double u2 = -signed_squared_distance<double>(o + t * d, *v[0], *v[1], *v[2], c.b1, c.b2, edges) * inv_w2;
    if (!(u2 < kRegularizationCut)) return;  // alpha below e^-kCut (or 0, or NaN)
    SoftCandidate k{shape, triangle, t, 0.0, -kInf, true, cos, edges};
    if (u2 > 0) {  // outside: a blurred margin
      k.inside = false;
      k.log_alpha = -u2;
      k.log_transmit = std::log(-std::expm1(-u2));
    }
    out.candidates.push_back(k);
  });
  // Front to back (a fixed order: Embree's is not), and nothing behind the first term crossed inside.
  std::sort(out.candidates.begin(), out.candidates.end(), [](const SoftCandidate& a, const SoftCandidate& b) {
    return a.t < b.t || (a.t == b.t && (a.shape < b.shape || (a.shape == b.shape && a.triangle < b.triangle)));
  });
  const auto first_inside =
      std::find_if(out.candidates.begin(), out.candidates.end(), [](const SoftCandidate& c) { return c.inside; });
  if (first_inside != out.candidates.end()) out.candidates.erase(first_inside + 1, out.candidates.end());
  out.weights.resize(out.candidates.size());
  double log_front = 0;
  for (size_t k = 0; k < out.candidates.size(); ++k) {
    out.weights[k] = std::exp(out.candidates[k].log_alpha + log_front);
    log_front += out.candidates[k].log_transmit;
  }
  out.background = std::exp(log_front);  // 0 behind a term crossed inside
}

int pick_soft_candidate(const SoftRay& ray, double u) {
  double acc = 0;
  for (size_t k = 0; k < ray.weights.size(); ++k) {
    acc += ray.weights[k];
    if (u < acc) return int(k);
  }
  if (ray.background > 0) return -1;
  // The weights sum to 1 up to rounding: the last term with a weight, which rounding alone missed.
  for (size_t k = ray.weights.size(); k-- > 0;)
    if (ray.weights[k] > 0) return int(k);
  return -1;
}

}  // namespace qsil
