#pragma once
/// @file attached_camera.h
/// Camera hits attached to the surface (docs/architecture.md §4 "Attached camera hits"): the
/// interior term of a camera sample that hits a moving shape is taken along a warp of the film
/// that carries the sample with the surface point it hits, instead of along the fixed camera ray.
///
/// Why: along a fixed ray the hit point slides over the surface at 1/cos of the surface's speed,
/// and the shading normal turns with it at the surface's curvature; under a glossy lobe the
/// per-sample derivative then has a heavy tail (docs/experiments/2026-11-28-attached-camera.md).
/// A hit attached to its material point does not slide: its normal only moves as the surface does.
///
/// The estimator (Reynolds transport over the pixel; Loubet et al. 2019 and Bangaru et al. 2020 use
/// the same identity for warps of the whole sphere, Zeltner et al. 2021 §4 calls the two forms
/// detached and attached). The pixel integral I = ∫ L(u) du over film position u (pixels) is
/// the same after the change of variables S(u) = u + theta w(u) V(u):
///   dI/dtheta = ∫ [∂L/∂theta + ∇L · (w V) + L div(w V)] du + Σ_discontinuities ∫ Δ[L (v_∂ - w V)]·n dl,
/// - V(u): the film velocity (pixels per unit theta) of the material point that the ray through u
///   hits, that point moving with its triangle's vertices (fixed barycentrics); 0 on a static
///   shape and where the ray escapes;
/// - w(u) = b(u) a(x): b a bump over the pixel, 1 inside, falling smoothly (C1) to 0 on the
///   pixel's border within kAttachedBorder of it, so that the warp maps the pixel onto itself (no
///   border term); a(x) in [0, 1] at the hit point x, continuous over the mesh (CameraAttachment);
/// - the first two terms are the path's derivative along the warped camera direction (its hit
///   then moves by (1 - w) of its slide along the ray plus w of the material point's velocity),
///   the third the warp's Jacobian;
/// - the last sum is the primary boundary term with, on each side of a discontinuity, the edge's
///   film velocity less the side's own w V (primary_boundary.cpp): where w V is continuous,
///   nothing changes; at a silhouette of the attached shape, its side's part is (1 - w) of what it
///   was; at a static silhouette with an attached shape behind it, a flux appears that the
///   detached form does not have, so the primary term samples static edges too.
/// w V is continuous inside every region of continuity of L (V is continuous across the edges of
/// a mesh whose vertices move, b is smooth, a is interpolated from the vertices), so no other term
/// exists.
/// Pdfs carry no derivative: the sample is placed at u by the detached pixel sampler, as every
/// sample is; only the integrand is transformed.
/// A control variate (CameraAttachment::control): the Jacobian term and the flux take L - c, c a
/// per-pixel constant fixed at set-up; c's parts of the two cancel, so any such c is unbiased.

#include "qsil/check.h"
#include "qsil/dual.h"
#include "qsil/error.h"
#include "qsil/integrators/geometry_view.h"
#include "qsil/integrators/path_tracer.h"
#include "qsil/scene.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <queue>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace qsil {

/// Width (fraction of a pixel) of the band along each pixel border where the attachment bump b
/// falls from 1 to 0. Chosen by measurement (docs/experiments/2026-11-28-attached-camera.md): the
/// detached form keeps 1 - b of the tail, the warp's Jacobian grows as 1/width.
inline constexpr double kAttachedBorder = 0.15;

/// The bump b over a pixel along one axis at offset s in [0, 1]: 1 on [k, 1 - k], 0 at 0 and 1,
/// smoothstep (C1) in between (k = kAttachedBorder). Over T (double, or a dual over film position).
template <class T>
T attached_bump_1d(const T& s) {
  constexpr double k = kAttachedBorder;
  double sv;
  if constexpr (std::is_same_v<T, double>)
    sv = s;
  else
    sv = s.value();
  auto step = [](const T& t) -> T { return T(t * t * (T(3.0) - T(2.0) * t)); };
  if (sv < k) return step(s / k);
  if (sv > 1.0 - k) return step((T(1.0) - s) / k);
  return T(1.0);
}

/// Samples per pixel of the primal pre-pass that sets the attached form's control variate
/// (CameraAttachment::control, set_attached_control), by default (EstimatorConfig::
/// camera_control_spp, `--camera-control-spp`, qsil.grad's camera_control_spp); chosen in
/// docs/experiments/2026-11-28-jacobian-control-variate.md.
inline constexpr int kAttachedControlSpp = 4;

/// Throws qsil::Error unless `spp` is a valid pre-pass size of the control variate
/// (EstimatorConfig::camera_control_spp, ReverseConfig::camera_control_spp): 0 (none) or at least 2
/// (its shrinkage needs the samples' variance).
inline void check_camera_control_spp(int spp) {
  if (spp != 0 && spp < 2)
    throw Error("the camera hits' control variate needs 0 (none) or at least 2 pre-pass spp (got " +
                std::to_string(spp) + ")");
}

/// Which camera samples are attached (EstimatorConfig::camera_hits, `--camera-hits`).
enum class CameraHits {
  Detached,  ///< none: the camera ray fixed (qsil's parametrization before 2026-11-28)
  Adaptive,  ///< where the normal turns fast under a narrow lobe (camera_attachment): the default
  Attached,  ///< every hit on a moving shape (strength 1): to compare, and to test the flux terms
};

/// The CameraHits named `name` ("adaptive", "attached", "detached"); throws qsil::Error naming it
/// otherwise.
inline CameraHits camera_hits_named(const std::string& name) {
  if (name == "adaptive") return CameraHits::Adaptive;
  if (name == "attached") return CameraHits::Attached;
  if (name == "detached") return CameraHits::Detached;
  throw Error("camera hits must be adaptive, attached or detached (got '" + name + "')");
}

/// Where the normal turns by at least kAttachedTurnStart lobe widths across a pixel, camera hits
/// start to be attached; from kAttachedTurnFull on, fully (attachment_strength; measured in
/// docs/experiments/2026-11-28-attached-camera.md).
inline constexpr double kAttachedTurnStart = 1.5;
inline constexpr double kAttachedTurnFull = 3.0;
/// The lobe width (radians of normal turn) of a diffuse BSDF in the adaptive rule: a diffuse shape
/// is attached where its normal's rms turn within a pixel (CameraAttachment) is at least 1.5 rad,
/// fully from 3 rad (measured on 12 scenes: 0.5 with the edge's whole angle as the turn lost 2x on
/// `shadow-quad`'s coarse bunny at 128²; 1.25 gave back part of the crease scenes' gain;
/// docs/experiments/2026-11-28-diffuse-crease-rule.md).
inline constexpr double kDiffuseLobeWidth = 1.0;
/// The strength falls by at most 1 per kAttachedRampPixels pixels of surface (the ramp, below).
inline constexpr double kAttachedRampPixels = 1.0;

/// The attachment a(x) of camera hits on each shape: a per-vertex strength in [0, 1], interpolated
/// over each triangle (so a is continuous across the mesh's edges, piecewise linear).
///
/// Why per vertex and where: the detached form's tail is the shading normal turning as the hit
/// slides, large where the normal turns by more than a lobe width across one pixel; elsewhere the
/// attached form only adds the noise of the warp's Jacobian (about L |V| / kAttachedBorder per
/// sample, on every attached pixel). So a vertex's strength is
/// smoothstep((m - kAttachedTurnStart) / (kAttachedTurnFull - kAttachedTurnStart)) with m = turn /
/// alpha, turn the largest over the vertex's edges of the turn of the normal along the edge within a
/// pixel (below), and alpha the lobe width:
/// - rough conductor (a thin, curved, glossy object): turn = angle s / len, the edge's angle between
///   its vertex normals per unit length (len) times s, the width of a pixel at the vertex's depth
///   (scene units): a curvature sustained over the pixel; alpha the GGX alpha;
/// - diffuse (a smoothed crease: a mesh without normals whose averaged vertex normals span a sharp
///   edge, docs/experiments/2026-11-25-tail-decomposition.md): turn = angle min(sqrt(s / len),
///   s / len): s times the root mean square over the pixel of the rate at which the normal turns
///   along the edge (for an edge shorter than a pixel, more than the edge's own angle); alpha
///   kDiffuseLobeWidth. An edge longer than a pixel turns by angle s / len within one, as above.
///   One that fits in a pixel turns by its whole angle across a band len / s of the pixel, where the
///   detached derivative is about angle / len: the pixel's second moment grows as angle² s / len,
///   and its root mean square, angle sqrt(s / len), is what compares with the Jacobian's noise
///   (which does not grow as the crease narrows). The rule before 2026-11-28, evening, took the
///   edge's whole angle with a lobe of 0.5 rad and attached the 45-90 degree turns of a coarse
///   mesh's edges a pixel long, where the Jacobian cost more than it removed (`shadow-quad`'s bunny
///   at 128²: twice the variance). The wider lobe is what leaves those edges detached; the square
///   root keeps the creases much narrower than a pixel above the threshold. kappa s would attach
///   every small, curved detail of a diffuse shape, and under a sun that loses
///   (docs/experiments/2026-11-28-diffuse-creases.md, 2026-11-28-diffuse-crease-rule.md).
/// Then the ramp: a vertex's strength is raised to at least a neighbour's minus len / (s
/// kAttachedRampPixels) (a Lipschitz bound, taken by a best-first pass from the strongest
/// vertices), so the strength never rises from 0 to 1 across a triangle much smaller than a
/// pixel: the warp's Jacobian holds div(a V), whose term V . grad a would be that steep.
/// 0 on static shapes and on flat-shaded ones (their normal does not turn within a face).
struct CameraAttachment {
  std::vector<std::vector<double>> strength;  ///< [shape][vertex]; empty for a shape never attached
  /// The control variate c of the attached form, per pixel (row-major, `control_width` pixels a
  /// row; empty: c = 0 everywhere): the warp's Jacobian term L div(w V) and the attached flux take
  /// L - c instead of L (AttachedCameraRay::apply_jacobian, the primary term's attached flux).
  /// Unbiased for any c fixed before the run: over a pixel, c's part of the Jacobian term integrates
  /// to c times the sum of w V's jumps across the pixel's discontinuities (divergence theorem, w V = 0
  /// on the pixel's border), which is exactly c's part of the flux, with the opposite sign. Set by
  /// set_attached_control (attached_control.h); docs/experiments/2026-11-29-attached-control.md.
  std::vector<Color> control;
  int control_width = 0;  ///< pixels per row of `control` (the camera's width), 0 while it is empty
  /// c at pixel (px, py), both within the camera's film (zero where none was set).
  Color control_at(int px, int py) const {
    if (control.empty()) return Color::Zero();
    QSIL_DCHECK(px >= 0 && px < control_width && py >= 0 &&
                size_t(py) * size_t(control_width) + size_t(px) < control.size());
    return control[size_t(py) * size_t(control_width) + size_t(px)];
  }
  /// Whether triangle `triangle` of shape `shape` has a vertex of non-zero strength: whether a
  /// camera ray that hits it is attached (attached_camera_ray).
  bool touches(const Scene& scene, int shape, int triangle) const {
    if (shape < 0 || size_t(shape) >= strength.size()) return false;
    const auto& st = strength[size_t(shape)];
    if (st.empty()) return false;
    const Eigen::Vector3i& t = scene.shapes[size_t(shape)].mesh.triangles[size_t(triangle)];
    return st[size_t(t[0])] > 0 || st[size_t(t[1])] > 0 || st[size_t(t[2])] > 0;
  }
  /// Whether any vertex has a non-zero strength.
  bool any() const {
    for (const auto& s : strength)
      for (double v : s)
        if (v > 0) return true;
    return false;
  }
  /// The strength on triangle `triangle` of shape `shape` at barycentrics (b1, b2), over T.
  template <class T>
  T at(const Scene& scene, int shape, int triangle, const T& b1, const T& b2) const {
    if (shape < 0 || size_t(shape) >= strength.size() || strength[size_t(shape)].empty()) return T(0.0);
    const Eigen::Vector3i& tri = scene.shapes[size_t(shape)].mesh.triangles[size_t(triangle)];
    const auto& a = strength[size_t(shape)];
    return (T(1.0) - b1 - b2) * T(a[size_t(tri[0])]) + b1 * T(a[size_t(tri[1])]) + b2 * T(a[size_t(tri[2])]);
  }
};

/// The vertices next to each vertex of a mesh, compressed: vertex v's are next[first[v]] ..
/// next[first[v + 1] - 1], one entry per triangle edge at v (an interior edge is listed twice), in
/// triangle order.
struct VertexNeighbours {
  std::vector<int> first;  ///< num_vertices + 1 offsets into next
  std::vector<int> next;   ///< 6 per triangle
  /// Throws qsil::Error for a mesh of more than INT_MAX / 6 triangles (int offsets).
  explicit VertexNeighbours(const TriangleMesh& m) : first(m.positions.size() + 1, 0) {
    if (m.triangles.size() > size_t(std::numeric_limits<int>::max() / 6))
      throw Error("camera attachment: " + std::to_string(m.triangles.size()) +
                  " triangles in one mesh, more than its neighbour table holds");
    for (const Eigen::Vector3i& t : m.triangles)
      for (int k = 0; k < 3; ++k) first[size_t(t[k]) + 1] += 2;
    for (size_t v = 1; v < first.size(); ++v) first[v] += first[v - 1];
    next.resize(size_t(first.back()));
    std::vector<int> fill(first.begin(), first.end() - 1);
    for (const Eigen::Vector3i& t : m.triangles)
      for (int e = 0; e < 3; ++e) {
        const int i = t[e], j = t[(e + 1) % 3];
        next[size_t(fill[size_t(i)]++)] = j;
        next[size_t(fill[size_t(j)]++)] = i;
      }
  }
  std::span<const int> of(int v) const {
    return {next.data() + first[size_t(v)], size_t(first[size_t(v) + 1] - first[size_t(v)])};
  }
};

/// Raises `a` (per vertex of `m`, in [0, 1]) to its smallest values with a_j >= a_i - len_ij /
/// (pixel_i kAttachedRampPixels) along every edge (i, j) of `m` (`next`: its vertices'
/// neighbours), pixel_i > 0 (pixel: a pixel's width at each vertex, scene units; 0 behind the
/// camera, where a vertex raises no neighbour). Best-first from the strongest vertex (Dijkstra's
/// order on 1 - a), O(E log V).
inline void attachment_ramp(const TriangleMesh& m, const VertexNeighbours& next, const std::vector<double>& pixel,
                            std::vector<double>& a) {
  const size_t n = m.positions.size();
  std::priority_queue<std::pair<double, int>> queue;
  for (size_t v = 0; v < n; ++v)
    if (a[v] > 0) queue.push({a[v], int(v)});
  while (!queue.empty()) {
    const auto [value, i] = queue.top();
    queue.pop();
    if (value < a[size_t(i)] || !(pixel[size_t(i)] > 0)) continue;  // stale entry, or behind the camera
    for (const int j : next.of(i)) {
      const double len = (m.positions[size_t(i)] - m.positions[size_t(j)]).norm();
      const double raised = value - len / (pixel[size_t(i)] * kAttachedRampPixels);
      if (raised > a[size_t(j)]) {
        a[size_t(j)] = raised;
        queue.push({raised, j});
      }
    }
  }
}

/// The attachment of `scene`'s camera hits on its `moving` shapes (above) for CameraHits::Adaptive;
/// strength 1 on every moving shape for CameraHits::Attached; none for CameraHits::Detached.
inline CameraAttachment camera_attachment(const Scene& scene, const std::vector<bool>& moving, CameraHits hits) {
  CameraAttachment out;
  out.strength.resize(scene.shapes.size());
  const Camera& cam = scene.camera;
  const double pixel_angle = 2.0 * cam.tan_half_fov().x() / cam.width;  // pixel width per unit depth
  if (hits == CameraHits::Detached) return out;
  for (size_t s = 0; s < scene.shapes.size(); ++s) {
    const Shape& shape = scene.shapes[s];
    if (s >= moving.size() || !moving[s]) continue;
    if (hits == CameraHits::Attached) {
      out.strength[s].assign(shape.mesh.positions.size(), 1.0);
      continue;
    }
    if (shape.face_normals || shape.mesh.normals.empty() || shape.bsdf < 0) continue;
    const BSDFDesc& b = scene.bsdfs[size_t(shape.bsdf)];
    const bool diffuse = b.type == BSDFDesc::Type::Diffuse;
    const double alpha = diffuse ? kDiffuseLobeWidth : std::max(b.alpha, 1e-3);
    const TriangleMesh& m = shape.mesh;
    const VertexNeighbours next(m);
    // Per vertex, in parallel: s, a pixel's width at the vertex (0 behind), then the turn (the
    // largest over its edges; an edge's length and angle are taken from its smaller vertex index,
    // so that both ends see the same numbers under any floating-point contraction) and the
    // strength before the ramp.
    std::vector<double> pixel(m.positions.size(), 0.0);
    tbb::parallel_for(size_t(0), pixel.size(),
                      [&](size_t v) { pixel[v] = std::max(0.0, cam.to_camera(m.positions[v]).z()) * pixel_angle; });
    std::vector<double> a(m.positions.size(), 0.0);
    tbb::parallel_for(0, int(a.size()), [&](int v) {
      const double sv = pixel[size_t(v)];
      double turn = 0.0;
      for (const int j : next.of(v)) {
        const int lo = std::min(v, j), hi = std::max(v, j);
        const double len = (m.positions[size_t(lo)] - m.positions[size_t(hi)]).norm();
        const Vec3 &ni = m.normals[size_t(lo)], &nj = m.normals[size_t(hi)];
        const double angle = std::atan2(ni.cross(nj).norm(), ni.dot(nj));
        if (!(len > 0)) continue;
        turn = std::max(turn, diffuse ? angle * std::min(std::sqrt(sv / len), sv / len) : angle * sv / len);
      }
      if (!(sv > 0)) return;
      const double x =
          std::clamp((turn / alpha - kAttachedTurnStart) / (kAttachedTurnFull - kAttachedTurnStart), 0.0, 1.0);
      a[size_t(v)] = x * x * (3.0 - 2.0 * x);
    });
    const bool any = std::any_of(a.begin(), a.end(), [](double x) { return x > 0; });
    if (any) attachment_ramp(m, next, pixel, a);
    if (any) out.strength[s] = std::move(a);
  }
  return out;
}

/// The velocity (3 x N) of the material point at barycentrics (b1, b2) of triangle `triangle` of
/// shape `shape`: its vertices' velocities interpolated.
template <int N>
Eigen::Matrix<double, 3, N> material_velocity(const SceneVelocities& vel, const Scene& scene, int shape, int triangle,
                                              double b1, double b2) {
  const Eigen::Vector3i& tri = scene.shapes[size_t(shape)].mesh.triangles[size_t(triangle)];
  const auto& P = vel.position[size_t(shape)];
  return (1.0 - b1 - b2) * P[size_t(tri[0])].template leftCols<N>() + b1 * P[size_t(tri[1])].template leftCols<N>() +
         b2 * P[size_t(tri[2])].template leftCols<N>();
}

/// A camera sample's warped direction: unit in value (the camera ray's own), its derivatives
/// d(direction)/du · w V per parameter; the warp's Jacobian, value 1, derivatives div(w V); and the
/// control variate c of its pixel (CameraAttachment::control).
template <int N>
struct AttachedCameraRay {
  Vec3T<Dual<N>> dir;
  Dual<N> jacobian;
  bool moves = false;             ///< false: the detached sample (zero derivatives, Jacobian 1)
  Color control = Color::Zero();  ///< the pixel's c, taken from L in the Jacobian term (apply_jacobian)
  /// The direction for PathRay::moving_dir: &dir, or null for the detached sample.
  const Vec3T<Dual<N>>* moving_dir() const { return moves ? &dir : nullptr; }
  /// The detached sample along unit direction `d`: fixed direction, Jacobian 1.
  static AttachedCameraRay detached(const Vec3& d) {
    AttachedCameraRay r{lift<Dual<N>>(d), Dual<N>(1.0), false};
    r.jacobian.derivatives().setZero();
    return r;
  }
  /// L's derivatives plus (L - c) div(w V): L times the Jacobian, less the control's part (L
  /// unchanged for the detached sample).
  void apply_jacobian(ColorT<Dual<N>>& L) const {
    if (moves)
      for (int k = 0; k < 3; ++k) {
        L[k] = L[k] * jacobian;
        L[k].derivatives() -= control[k] * jacobian.derivatives();
      }
  }
};

/// The attached camera ray of the sample at film position `film` (pixels) in pixel (px, py), whose
/// camera ray `ray` (trace_camera_ray) was traced and hit a triangle that the attachment touches,
/// w = b(u) a(x) (`attachment`), for `num_params` (<= N) parameters whose velocities of the hit
/// triangle's three vertices are `vertex_velocity` (3 x N each, world units per unit parameter, in
/// the triangle's vertex order; columns from num_params on are ignored). The material point at
/// barycentrics (b0, b1, b2) moves at b0 v0 + b1 v1 + b2 v2. Forward mode gives the scene's
/// velocities (attached_camera_ray); reverse mode a unit velocity per vertex coordinate (N = 9:
/// column 3 i + j moves vertex i along axis j), whose results are the local Jacobians of the
/// warped direction and of div(w V). Where the ray meets its triangle's plane at a grazing angle
/// where the arithmetic overflows (a set of measure zero), the detached sample.
template <int N>
AttachedCameraRay<N> attached_camera_warp(const Scene& scene, const CameraAttachment& attachment, const CameraRay& ray,
                                          const Vec2& film, int px, int py,
                                          const std::array<Eigen::Matrix<double, 3, N>, 3>& vertex_velocity,
                                          int num_params) {
  AttachedCameraRay<N> r = AttachedCameraRay<N>::detached(ray.dir);
  // Over film position u = (u_x, u_y): A is a dual in the two film coordinates.
  using A = Eigen::AutoDiffScalar<Eigen::Vector2d>;
  using V3 = Eigen::Matrix<A, 3, 1>;
  const Camera& cam = scene.camera;
  const A ux(film.x(), 2, 0), uy(film.y(), 2, 1);
  const Vec2 tf = cam.tan_half_fov();
  const Eigen::Matrix3d R = cam.to_world.block<3, 3>(0, 0);
  V3 q_local((A(1.0) - A(2.0 / cam.width) * ux) * A(tf.x()), (A(1.0) - A(2.0 / cam.height) * uy) * A(tf.y()), A(1.0));
  V3 q;
  for (int i = 0; i < 3; ++i) q[i] = A(R(i, 0)) * q_local[0] + A(R(i, 1)) * q_local[1] + A(R(i, 2)) * q_local[2];
  // ---- The ray through u meets the plane of the hit triangle (Moller-Trumbore, barycentrics
  // extrapolated off the triangle: a smooth function of u).
  const Shape& shape = scene.shapes[size_t(ray.hit.shape)];
  const Eigen::Vector3i& tri = shape.mesh.triangles[size_t(ray.hit.triangle)];
  const Vec3 &X0 = shape.mesh.positions[size_t(tri[0])], &X1 = shape.mesh.positions[size_t(tri[1])],
             &X2 = shape.mesh.positions[size_t(tri[2])];
  const Vec3 e1 = X1 - X0, e2 = X2 - X0, tv = cam.origin() - X0, qv = tv.cross(e1);
  auto lift_a = [](const Vec3& v) { return V3(A(v.x()), A(v.y()), A(v.z())); };
  const V3 pvec = q.cross(lift_a(e2));
  const A inv_det = A(1.0) / lift_a(e1).dot(pvec);
  const A b1 = lift_a(tv).dot(pvec) * inv_det;
  const A b2 = q.dot(lift_a(qv)) * inv_det;
  const A b0 = A(1.0) - b1 - b2;
  const V3 y = lift_a(X0) + lift_a(e1) * b1 + lift_a(e2) * b2;
  // ---- w(u) and the film velocity of the material point, as duals in u.
  const A w = attached_bump_1d(A(ux - A(double(px)))) * attached_bump_1d(A(uy - A(double(py)))) *
              attachment.at(scene, ray.hit.shape, ray.hit.triangle, b1, b2);
  const Eigen::Matrix3d Rt = R.transpose();
  V3 c;
  const Vec3 o = cam.origin();
  for (int i = 0; i < 3; ++i)
    c[i] = A(Rt(i, 0)) * (y[0] - A(o.x())) + A(Rt(i, 1)) * (y[1] - A(o.y())) + A(Rt(i, 2)) * (y[2] - A(o.z()));
  // d(unit direction)/du (3 x 2) at u: from q, whose norm does not change what it points at.
  const Vec3 qv0(q[0].value(), q[1].value(), q[2].value());
  const double qn = qv0.norm();
  Eigen::Matrix<double, 3, 2> dq;
  for (int i = 0; i < 3; ++i) dq.row(i) = q[i].derivatives().transpose();
  const Eigen::Matrix<double, 3, 2> ddir = (Eigen::Matrix3d::Identity() - qv0 * qv0.transpose() / (qn * qn)) * dq / qn;
  Eigen::Matrix<double, N, 1> div = Eigen::Matrix<double, N, 1>::Zero();
  Eigen::Matrix<double, 3, N> dd = Eigen::Matrix<double, 3, N>::Zero();
  for (int k = 0; k < num_params; ++k) {
    V3 dy;
    for (int i = 0; i < 3; ++i)
      dy[i] = b0 * A(vertex_velocity[0](i, k)) + b1 * A(vertex_velocity[1](i, k)) + b2 * A(vertex_velocity[2](i, k));
    V3 dc;
    for (int i = 0; i < 3; ++i) dc[i] = A(Rt(i, 0)) * dy[0] + A(Rt(i, 1)) * dy[1] + A(Rt(i, 2)) * dy[2];
    const A vx = A(-0.5 * cam.width / tf.x()) * (dc[0] * c[2] - c[0] * dc[2]) / (c[2] * c[2]);
    const A vy = A(-0.5 * cam.height / tf.y()) * (dc[1] * c[2] - c[1] * dc[2]) / (c[2] * c[2]);
    const A fx = w * vx, fy = w * vy;
    div[k] = fx.derivatives()[0] + fy.derivatives()[1];
    dd.col(k) = ddir * Vec2(fx.value(), fy.value());
  }
  if (!div.allFinite() || !dd.allFinite()) return r;
  for (int i = 0; i < 3; ++i) r.dir[i].derivatives() = dd.row(i).transpose();
  r.jacobian.derivatives() = div;
  r.moves = true;
  r.control = attachment.control_at(px, py);
  return r;
}

/// The attached camera ray of the sample at film position `film` (pixels) in pixel (px, py), whose
/// camera ray `ray` (trace_camera_ray) was traced, w = b(u) a(x) (`attachment`): attached_camera_warp
/// with the velocities the view's duals carry (`vel`). Where the ray escapes, hits a static shape
/// or a triangle whose three vertices have strength 0, or meets its triangle's plane at a grazing
/// angle where the arithmetic overflows (a set of measure zero), the direction is fixed and the
/// Jacobian 1: the detached sample.
template <int N>
AttachedCameraRay<N> attached_camera_ray(const Scene& scene, const SceneVelocities& vel,
                                         const CameraAttachment& attachment, const CameraRay& ray, const Vec2& film,
                                         int px, int py) {
  if (!ray.hit.valid() || !vel.moving[size_t(ray.hit.shape)] ||
      !attachment.touches(scene, ray.hit.shape, ray.hit.triangle))
    return AttachedCameraRay<N>::detached(ray.dir);
  const Eigen::Vector3i& tri = scene.shapes[size_t(ray.hit.shape)].mesh.triangles[size_t(ray.hit.triangle)];
  const auto& P = vel.position[size_t(ray.hit.shape)];
  std::array<Eigen::Matrix<double, 3, N>, 3> v;
  for (int i = 0; i < 3; ++i) {
    v[size_t(i)].setZero();
    v[size_t(i)].leftCols(vel.num_params) = P[size_t(tri[i])].leftCols(vel.num_params);
  }
  return attached_camera_warp<N>(scene, attachment, ray, film, px, py, v, vel.num_params);
}

}  // namespace qsil
