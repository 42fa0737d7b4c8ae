/// @file projective_boundary.cpp
/// See projective_boundary.h.

#include "projective_boundary.h"

#include "qsil/check.h"
#include "qsil/dual.h"
#include "qsil/error.h"
#include "qsil/integrators/edge_jump.h"
#include "qsil/integrators/geometry_view.h"
#include "qsil/sampling.h"
#include "sample_chunks.h"
#include "silhouette_projection.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <string>

namespace qsil {

namespace {

/// A uniform number in [0, 1) with 53 bits from two of the sampler's 32-bit ones: u.x picks an edge
/// and, as the remainder, t (boundary_segment), whose resolution would otherwise be 2^-32 over
/// the whole sample space (a lattice of a few thousand t on an edge of a large mesh).
double next53(Sampler& sampler) {
  const double hi = sampler.next(), lo = sampler.next();
  return std::min(hi + lo * 0x1p-32, std::nextafter(1.0, 0.0));
}

/// The seed of the guide's training segments (train_segment_guide): fixed, so that the guide
/// depends on the scene alone.
constexpr uint64_t kGuideSeed = 0x9e3779b97f4a7c15ULL;

/// The fewest training segments per cell of the guide (train_segment_guide).
constexpr double kGuideTrainingPerCell = 32;

/// Whether edge e is a discontinuity only along its silhouette lune: two faces, no crease.
bool lune_edge(const edgetree::Edge& e) {
  return e.f1 >= 0 && !e.crease && !e.crossing &&
         (e.cls == edgetree::EdgeClass::Convex || e.cls == edgetree::EdgeClass::Concave);
}

/// The angle (radians, [0, pi]) between the unit normals of edge e's two faces.
double face_angle(const edgetree::Edge& e) {
  const Vec3 n0 = e.q0.head<3>(), n1 = e.q1.head<3>();
  return std::atan2(n0.cross(n1).norm(), n0.dot(n1));
}

/// The frame about a lune edge e (lune_edge) in which its silhouette directions are azimuth
/// ranges: `a` along n0 (perpendicular to the edge), b = axis x a turned so that n1 lies at
/// azimuth psi1 in [0, pi]. (n0 . w)(n1 . w) < 0 exactly for azimuths in (pi/2, pi/2 + psi1) and
/// that wedge turned by pi.
struct LuneFrame {
  Vec3 axis, a, b;
  double psi1 = 0;
};
LuneFrame lune_frame(const edgetree::Edge& e) {
  LuneFrame f;
  f.axis = (e.p1 - e.p0).normalized();
  const Vec3 n0 = e.q0.head<3>(), n1 = e.q1.head<3>();
  f.a = (n0 - n0.dot(f.axis) * f.axis).normalized();
  f.b = f.axis.cross(f.a);
  f.psi1 = std::atan2(n1.dot(f.b), n1.dot(f.a));
  if (f.psi1 < 0) {
    f.b = -f.b;
    f.psi1 = -f.psi1;
  }
  return f;
}

/// A vertex of the walk from p toward the camera: its hit, its interaction (detached) and the
/// direction (unit, world) light arrives from: the edge point for p, the previous vertex after.
struct WalkVertex {
  Hit hit;
  SurfaceInteraction<double> si;
  Vec3 wi = Vec3::Zero();
};

/// The connection to the camera kept by reservoir sampling: its vertex, pixel, weight (importance
/// chain times F toward the camera times We, over the segment's pdf) and p's viewer direction on
/// its path.
struct Connection {
  int vertex = -1;
  int px = 0, py = 0;
  Color weight = Color::Zero();
  Vec3 wo_p = Vec3::Zero();
};

/// p's velocity (3 x N) along the camera path of a connection kept at walk vertex `last`: the path
/// camera -> walk[last] -> ... -> walk[0] = p retraced with duals, its directions fixed (the
/// interior term's parametrization; each vertex's hit recomputed along the fixed direction).
template <int N>
Eigen::Matrix<double, 3, N> shading_point_velocity(const PathContext& ctx, const SceneVelocities& vel,
                                                   const std::array<WalkVertex, kUnboundedDepthCap>& walk, int last) {
  using D = Dual<N>;
  const DualView<N> view{ctx.scene, &vel};
  auto along = [&](int i, const Vec3T<D>& origin) {
    const Vec3 dir = (walk[size_t(i)].si.p - value(origin)).normalized();
    return make_interaction(view, walk[size_t(i)].hit, origin, dir, ctx.tracer->local_origin());
  };
  SurfaceInteraction<D> si = along(last, lift<D>(ctx.scene->camera.origin()));
  for (int i = last - 1; i >= 0; --i) si = along(i, si.p);
  Eigen::Matrix<double, 3, N> dp;
  for (int a = 0; a < 3; ++a) dp.row(a) = si.p[a].derivatives().transpose();
  return dp;
}

/// What the camera and the tracer give every segment of a run.
struct SegmentContext {
  const PathContext& ctx;
  const SceneVelocities& vel;
  const ProjectiveEdges& edges;
  double fx = 0, fy = 0;
  Vec3 o, forward;
  SegmentContext(const PathContext& c, const SceneVelocities& v, const ProjectiveEdges& e) : ctx(c), vel(v), edges(e) {
    const Camera& cam = c.scene->camera;
    const Vec2 tanf = cam.tan_half_fov();
    fx = cam.width / (2.0 * tanf.x());
    fy = cam.height / (2.0 * tanf.y());
    o = cam.origin();
    forward = cam.to_world.block<3, 1>(0, 2).normalized();
  }
};

/// A contributing boundary segment: the pixel its connection lands in, its weight (importance x F x
/// jump over the segment's density, per sample: the pixel's derivative k gains c J[k]) and J.
template <int N>
struct SegmentValue {
  int px = 0, py = 0;
  Color c = Color::Zero();
  Eigen::Matrix<double, 1, N> J;
  /// What a guide learns from the segment: |c| summed over the channels times |J| summed over the
  /// parameters.
  double magnitude() const { return c.abs().sum() * J.cwiseAbs().sum(); }
};

/// The boundary segment of u (boundary_segment), drawn with density pdf x `density`, evaluated:
/// the shading point, the walk toward the camera with its reservoir, the jump and its Jacobian
/// (the file comment of projective_boundary.h). Nothing for a zero contribution (counted in
/// stats.boundary_zero). Draws the walk's and the jump's numbers from `sampler`.
template <int N>
std::optional<SegmentValue<N>> evaluate_segment(const SegmentContext& sc, const Vec3& u, double density,
                                                Sampler& sampler, std::array<WalkVertex, kUnboundedDepthCap>& walk,
                                                PathStats& stats) {
  const PathContext& ctx = sc.ctx;
  const Camera& cam = ctx.scene->camera;
  const PrimalView pv{ctx.scene};
  const Vec3& local_origin = ctx.tracer->local_origin();
  const Vec3& o = sc.o;
  ++stats.boundary_traversals;
  const BoundarySegment seg = boundary_segment(sc.edges, u);
  const double pdf = seg.pdf * density;  // per unit t and steradian
  const edgetree::Edge& e = *sc.edges.edges[seg.edge];
  const double t = seg.t;
  const Vec3& w = seg.direction.w;
  if (!(pdf > 0)) {
    ++stats.boundary_zero;
    return std::nullopt;
  }
  // ---- The shading point p: the first hit from the edge point along -w (not the edge's faces).
  const Vec3 y = e.p0 + t * (e.p1 - e.p0);
  ++stats.rays;
  walk[0].hit = ctx.tracer->intersect(y, -w, kInf, edge_faces(e, false));
  if (!walk[0].hit.valid()) {
    ++stats.boundary_zero;
    return std::nullopt;
  }
  walk[0].si = make_interaction(pv, walk[0].hit, y, Vec3(-w), local_origin);
  walk[0].wi = w;
  const double s = walk[0].si.t, cos_p = std::abs(walk[0].si.ng.dot(w));
  if (!(s > 0 && cos_p > 0) || !walk[0].si.p.allFinite()) {
    ++stats.boundary_zero;
    return std::nullopt;
  }
  // ---- The walk toward the camera: connect each vertex, keep one connection (reservoir).
  Color beta = Color::Constant(s * s / (cos_p * pdf));
  Connection kept;
  int found = 0;
  for (int k = 0; k + 1 < ctx.max_depth; ++k) {
    const SurfaceInteraction<double>& si = walk[size_t(k)].si;
    const Vec3& wi = walk[size_t(k)].wi;
    const Vec3 to_cam = o - si.p;
    const double r = to_cam.norm();
    double depth = 0;
    const Vec2 film = cam.project(si.p, &depth);
    if (r > 0 && depth > 0 && film.x() >= 0 && film.x() < cam.width && film.y() >= 0 && film.y() < cam.height) {
      const Vec3 wc = to_cam / r;
      const double cos_theta = -wc.dot(sc.forward);
      const Color f = vertex_bsdf(ctx, si, wc).toward(wi);
      if (cos_theta > 0 && (f != 0).any()) {
        const Vec3 origin = spawn_origin(si, wc);
        ++stats.rays;
        if (!ctx.tracer->occluded(origin, wc, (o - origin).norm() * (1.0 - 1.0 / 4096.0), IgnoreSet{})) {
          ++found;
          if (sampler.next() * found < 1.0) {
            const double We = sc.fx * sc.fy / (cos_theta * cos_theta * cos_theta) * std::abs(si.ng.dot(wc)) / (r * r);
            kept = {k, std::clamp(int(film.x()), 0, cam.width - 1), std::clamp(int(film.y()), 0, cam.height - 1),
                    Color(beta * f * We), wc};
          }
        }
      }
    }
    if (k + 2 >= ctx.max_depth) break;  // a connection one vertex further would leave p no segment
    // A direction from the BSDF, proposed in the frame seen from wi (the one it reaches is
    // not known yet), mixed with the uniform sphere.
    const ShadingPoint<double> proposal = make_shading_point(ctx, si, wi);
    const Vec3 wi_local = proposal.frame_value.to_local(wi);
    const double choose = sampler.next();
    const Vec2 uv = sampler.next2();
    Vec3 u;
    if (choose < kProjectiveUniformShare) {
      u = square_to_uniform_sphere(uv);
    } else {
      // A proposal below the horizon (bs.valid false) is still a direction with density pdf,
      // which pdf_u counts (bsdf_pdf includes it): it is kept, not dropped. No direction at all
      // (the surface seen from behind) leaves only the uniform part, as pdf_u says.
      const BSDFSample bs = bsdf_sample(*proposal.bsdf, wi_local, uv);
      if (!(bs.pdf > 0)) break;
      u = proposal.frame_value.to_world(bs.wi).normalized();
    }
    const double pdf_u =
        kProjectiveUniformShare * uniform_sphere_pdf() +
        (1 - kProjectiveUniformShare) * bsdf_pdf(*proposal.bsdf, proposal.frame_value.to_local(u), wi_local);
    const Color f = vertex_bsdf(ctx, si, u).toward(wi);
    if (!(pdf_u > 0) || (f == 0).all()) break;
    const Vec3 origin = spawn_origin(si, u);
    ++stats.rays;
    const Hit next = ctx.tracer->intersect(origin, u, kInf, IgnoreSet{});
    if (!next.valid()) break;
    WalkVertex& v = walk[size_t(k + 1)];
    v.hit = next;
    v.si = make_interaction(pv, next, origin, u, local_origin);
    v.wi = -u;
    const double cos_in = std::abs(v.si.ng.dot(u));
    if (!(cos_in > 0) || !v.si.p.allFinite()) break;
    // Adjoint step: f_s cos at this vertex, the next one's |n_g . u| back to area, over the pdf.
    beta = beta * f * (std::abs(si.ng.dot(u)) / (pdf_u * cos_in));
  }
  if (found == 0) {
    ++stats.boundary_zero;
    return std::nullopt;
  }
  // ---- The jump at p for the kept connection's depth, and its Jacobian with p's velocity.
  const SurfaceInteraction<double>& p = walk[0].si;
  const Vec3 wo_p = kept.vertex == 0 ? kept.wo_p : Vec3(-walk[1].wi);
  const EdgeJumpInputs in = vertex_edge_inputs(ctx, e, t, p, wo_p, w, kept.vertex + 1);
  const Eigen::Matrix<double, 3, N> dp = shading_point_velocity<N>(ctx, sc.vel, walk, kept.vertex);
  Eigen::Matrix<double, 1, N> J;
  const std::optional<Color> jump = edge_jump_with(ctx, in, sampler, stats, [&](const Vec3& g) {
    J = edge_point_jacobian<N>(sc.vel, e, t, g, dp);
    return !J.isZero(0.0);
  });
  if (!jump || (*jump == 0).all()) {
    ++stats.boundary_zero;
    return std::nullopt;
  }
  return SegmentValue<N>{kept.px, kept.py, Color(kept.weight * *jump * double(found)), J};
}

/// Draws `count` boundary segments of chunk `chunk` from its stream (stream::kProjectiveSegments), their u from
/// `guide`, and appends their splats (forward mode, N >= the parameter count) to `out`; returns
/// the non-finite ones.
template <int N>
uint64_t run_chunk(const SegmentContext& sc, const SegmentGuide& guide, long long count, double per_sample,
                   uint64_t seed, long long chunk, std::vector<FilmSplat>& out, PathStats& stats) {
  const int K = sc.vel.num_params;
  const FilmLayout layout(K);
  uint64_t nonfinite = 0;
  std::array<WalkVertex, kUnboundedDepthCap> walk;
  Sampler sampler(seed, uint64_t(chunk), 0, stream::kProjectiveSegments);
  for (long long i = 0; i < count; ++i) {
    Vec3 u;
    if (guide.uniform()) {
      const double ux = next53(sampler);
      // Sequenced draws, z before y: the order GCC gave the unsequenced constructor arguments
      // these were first drawn as, so that outputs stay as they were, now on any compiler.
      const double uz = sampler.next(), uy = sampler.next();
      u = Vec3(ux, uy, uz);
    } else {
      const double choose = sampler.next(), pick = sampler.next();
      const double wx = next53(sampler);
      const double wz = sampler.next(), wy = sampler.next();  // as above
      const Vec3 within(wx, wy, wz);
      u = guide.sample(choose, pick, within);
    }
    const std::optional<SegmentValue<N>> v = evaluate_segment<N>(sc, u, guide.density(u), sampler, walk, stats);
    if (!v) continue;
    const Color c = v->c * per_sample;
    if (!c.allFinite() || !v->J.allFinite()) {
      ++nonfinite;
      continue;
    }
    for (int k = 0; k < K; ++k) {
      for (int ch = 0; ch < 3; ++ch) out.push_back({v->px, v->py, layout.derivative(k, ch), c[ch] * v->J[k]});
      out.push_back({v->px, v->py, layout.derivative_mean(k), c.mean() * v->J[k]});
    }
  }
  return nonfinite;
}

/// Draws `count` uniform training segments of chunk `chunk` from its stream (stream::kProjectiveTraining)
/// and adds each one's |value| (summed over parameters and channels) to its cell of `sums`.
template <int N>
void train_chunk(const SegmentContext& sc, int resolution, long long count, long long chunk, std::vector<double>& sums,
                 PathStats& stats) {
  std::array<WalkVertex, kUnboundedDepthCap> walk;
  Sampler sampler(kGuideSeed, uint64_t(chunk), 0, stream::kProjectiveTraining);
  const SegmentGuide cells(resolution, std::vector<double>(size_t(resolution) * resolution * resolution, 0.0), 1.0);
  for (long long i = 0; i < count; ++i) {
    const double ux = next53(sampler);
    const double uz = sampler.next(), uy = sampler.next();  // z before y, as run_chunk
    const Vec3 u(ux, uy, uz);
    const std::optional<SegmentValue<N>> v = evaluate_segment<N>(sc, u, 1.0, sampler, walk, stats);
    if (!v) continue;
    const double value = v->magnitude();
    if (std::isfinite(value)) sums[size_t(cells.cell(u))] += value;
  }
}

/// The seeds of `count` camera paths of chunk `chunk` from its stream (stream::kProjectiveSeeds)
/// (train_projected_guide): each projected seed's u and the estimator's |value| there, appended
/// to `out` in order.
template <int N>
void seed_chunk(const SegmentContext& sc, const TriangleEdges& tri, long long count, long long chunk,
                std::vector<std::pair<Vec3, double>>& out, PathStats& stats) {
  const PathContext& ctx = sc.ctx;
  const Camera& cam = ctx.scene->camera;
  const PrimalView pv{ctx.scene};
  const Vec3& local_origin = ctx.tracer->local_origin();
  std::array<WalkVertex, kUnboundedDepthCap> walk;
  Sampler sampler(kGuideSeed, uint64_t(chunk), 0, stream::kProjectiveSeeds);
  auto seed = [&](const Vec3& x, const Hit& hit) {
    const std::optional<Vec3> u = project_seed(ctx, sc.edges, tri, x, hit, sampler, stats);
    if (!u) return;
    const std::optional<SegmentValue<N>> v = evaluate_segment<N>(sc, *u, 1.0, sampler, walk, stats);
    const double value = v ? v->magnitude() : 0.0;
    if (std::isfinite(value)) out.push_back({*u, value});
  };
  for (long long i = 0; i < count; ++i) {
    // A film position uniform over the image, as a pixel and the offset in it (both exact).
    const double fy = sampler.next() * cam.height, fx = sampler.next() * cam.width;  // y first, as run_chunk
    const int x = int(fx), y = int(fy);
    const CameraRay ray = trace_camera_ray(ctx, x, y, Vec2(fx - x, fy - y), stats);
    if (!ray.hit.valid()) continue;
    const Vec3& d = ray.dir;
    SurfaceInteraction<double> si = make_interaction(pv, ray.hit, sc.o, d, local_origin);
    Vec3 wo = -d;
    // Vertex k of the path (k = 1: the camera ray's hit) is a shading point while a segment is left.
    for (int k = 1; k < ctx.max_depth; ++k) {
      const Vec3 x = si.p;
      const LightDirection ld = sample_light_direction(ctx, x, sampler);
      if (ld.valid) {
        const Vec3 origin = spawn_origin(si, ld.wi);
        ++stats.rays;
        const Hit occluder =
            ctx.tracer->intersect(origin, ld.wi, ld.environment ? kInf : ld.dist * (1.0 - 1.0 / 4096.0));
        if (occluder.valid()) seed(x, occluder);
      }
      const ShadingPoint<double> sp = make_shading_point(ctx, si, wo);
      const BSDFSample bs = bsdf_sample(*sp.bsdf, sp.frame_value.to_local(wo), sampler.next2());
      if (!(bs.pdf > 0)) break;
      const Vec3 wi = sp.frame_value.to_world(bs.wi).normalized();
      const Vec3 origin = spawn_origin(si, wi);
      ++stats.rays;
      const Hit next = ctx.tracer->intersect(origin, wi);
      if (!next.valid()) break;
      seed(x, next);
      si = make_interaction(pv, next, origin, wi, local_origin);
      wo = -wi;
      if (!si.p.allFinite()) break;
    }
  }
}

}  // namespace

double edge_direction_measure(const edgetree::Edge& e) {
  if (e.retired) return 0.0;
  return lune_edge(e) ? 4.0 * face_angle(e) : 4.0 * kPi;
}

EdgeDirection sample_edge_direction(const edgetree::Edge& e, const Vec2& u) {
  EdgeDirection out;
  const double measure = edge_direction_measure(e);
  if (!(measure > 0)) return out;
  if (!lune_edge(e)) {
    out.w = square_to_uniform_sphere(u);
    out.pdf = 1.0 / measure;
    return out;
  }
  const LuneFrame f = lune_frame(e);
  const Vec3 &axis = f.axis, &a = f.a, &b = f.b;
  const double psi1 = f.psi1;
  const bool second = u.x() >= 0.5;
  const double v = second ? 2.0 * u.x() - 1.0 : 2.0 * u.x();
  const double psi = 0.5 * kPi + v * psi1 + (second ? kPi : 0.0);
  const double z = 2.0 * u.y() - 1.0, r = std::sqrt(std::max(0.0, 1.0 - z * z));
  out.w = (z * axis + r * (std::cos(psi) * a + std::sin(psi) * b)).normalized();
  out.pdf = 1.0 / measure;
  if (!out.w.allFinite()) out = {};
  return out;
}

ProjectiveEdges make_projective_edges(const edgetree::EdgeSet& edges, const std::vector<bool>& moving) {
  ProjectiveEdges out;
  std::vector<double> weight;
  std::vector<bool> is_moving;
  double moving_total = 0, static_total = 0;
  auto consider = [&](const edgetree::Edge& e) {
    const double wgt = (e.p1 - e.p0).norm() * edge_direction_measure(e);
    if (!(wgt > 0) || !std::isfinite(wgt)) return;
    const bool m = e.shape < 0 || e.shape >= int(moving.size()) || moving[size_t(e.shape)];
    out.edges.push_back(&e);
    weight.push_back(wgt);
    is_moving.push_back(m);
    (m ? moving_total : static_total) += wgt;
  };
  for (const auto& e : edges.edges()) consider(e);
  for (const auto& e : edges.always_edges()) consider(e);
  // Static edges hold kProjectiveStaticShare of the total when both kinds exist.
  const double static_scale = moving_total > 0 && static_total > 0
                                  ? kProjectiveStaticShare / (1 - kProjectiveStaticShare) * moving_total / static_total
                                  : 1.0;
  out.cdf.assign(1, 0.0);
  for (size_t i = 0; i < out.edges.size(); ++i)
    out.cdf.push_back(out.cdf.back() + weight[i] * (is_moving[i] ? 1.0 : static_scale));
  return out;
}

long long projective_samples_per_index(int width, int height, double ratio) {
  if (!(ratio > 0 && ratio <= 1024))
    throw Error("projective: boundary segments per pixel sample must be in (0, 1024] (got " + std::to_string(ratio) +
                ")");
  constexpr long long kChunk = ChunkPlan::kChunkSize;
  const double n = std::ceil(ratio * double(width) * double(height) / double(kChunk));
  return std::max(1LL, (long long)n) * kChunk;
}

BoundarySegment boundary_segment(const ProjectiveEdges& edges, const Vec3& u) {
  BoundarySegment seg;
  const std::vector<double>& cdf = edges.cdf;
  const double ue = u.x() * cdf.back();
  seg.edge = std::min(size_t(std::upper_bound(cdf.begin(), cdf.end(), ue) - cdf.begin()) - 1, edges.edges.size() - 1);
  const double width = cdf[seg.edge + 1] - cdf[seg.edge];
  if (!(width > 0)) return seg;
  seg.t = std::clamp((ue - cdf[seg.edge]) / width, 0.0, std::nextafter(1.0, 0.0));
  seg.direction = sample_edge_direction(*edges.edges[seg.edge], Vec2(u.y(), u.z()));
  seg.pdf = edges.probability(seg.edge) * seg.direction.pdf;
  return seg;
}

std::optional<Vec3> invert_boundary_segment(const ProjectiveEdges& edges, size_t edge, double t, const Vec3& w) {
  if (edge >= edges.edges.size()) return std::nullopt;
  const double width = edges.cdf[edge + 1] - edges.cdf[edge];
  if (!(width > 0)) return std::nullopt;
  const double ux =
      std::min((edges.cdf[edge] + std::clamp(t, 0.0, 1.0) * width) / edges.cdf.back(), std::nextafter(1.0, 0.0));
  const edgetree::Edge& e = *edges.edges[edge];
  if (!lune_edge(e)) {  // inverse of square_to_uniform_sphere
    double phi = std::atan2(w.y(), w.x());
    if (phi < 0) phi += 2.0 * kPi;
    return Vec3(ux, std::clamp(0.5 * (1.0 - w.z()), 0.0, std::nextafter(1.0, 0.0)),
                std::min(phi / (2.0 * kPi), std::nextafter(1.0, 0.0)));
  }
  // Inverse of sample_edge_direction's lune: the same frame about the edge.
  const LuneFrame f = lune_frame(e);
  const Vec3 &axis = f.axis, &a = f.a, &b = f.b;
  const double psi1 = f.psi1;
  if (!(psi1 > 0)) return std::nullopt;
  double psi = std::atan2(w.dot(b), w.dot(a)) - 0.5 * kPi;  // the first wedge is (0, psi1)
  if (psi < 0) psi += 2.0 * kPi;
  double v;
  bool second = false;
  if (psi < psi1) {
    v = psi / psi1;
  } else if (psi >= kPi && psi < kPi + psi1) {
    v = (psi - kPi) / psi1;
    second = true;
  } else {
    return std::nullopt;
  }
  const double uy = std::clamp(0.5 * (w.dot(axis) + 1.0), 0.0, std::nextafter(1.0, 0.0));
  const double uv = std::min(second ? 0.5 * (v + 1.0) : 0.5 * v, std::nextafter(1.0, 0.0));
  return Vec3(ux, uv, uy);
}

SegmentGuide::SegmentGuide(int resolution, const std::vector<double>& weights, double uniform_share)
    : resolution_(resolution), share_(uniform_share) {
  QSIL_CHECK(resolution > 0 && weights.size() == size_t(resolution) * resolution * resolution);
  QSIL_CHECK(uniform_share > 0 && uniform_share <= 1);
  cdf_.assign(1, 0.0);
  for (double w : weights) cdf_.push_back(cdf_.back() + (std::isfinite(w) && w > 0 ? w : 0.0));
  if (!(cdf_.back() > 0)) share_ = 1;  // nothing learnt: uniform
}

SegmentGuide SegmentGuide::octree(const std::vector<Vec3>& points, const std::vector<double>& values, int max_depth,
                                  int max_leaf, double uniform_share) {
  QSIL_CHECK(points.size() == values.size() && points.size() < size_t(std::numeric_limits<int>::max()) &&
             max_depth >= 0 && max_depth <= 20 && max_leaf >= 1);
  QSIL_CHECK(uniform_share > 0 && uniform_share <= 1);
  SegmentGuide g;
  g.share_ = uniform_share;
  g.cdf_.assign(1, 0.0);
  g.nodes_.emplace_back();
  // Depth first; a node's children are appended together, so octant o of node n is first + o.
  struct Pending {
    int node;
    std::vector<int> idx;
    Vec3 lo;
    double size;
    int depth;
  };
  std::vector<int> all(points.size());
  for (size_t i = 0; i < points.size(); ++i) all[i] = int(i);
  std::vector<Pending> stack;
  stack.push_back({0, std::move(all), Vec3::Zero(), 1.0, 0});
  while (!stack.empty()) {
    Pending n = std::move(stack.back());
    stack.pop_back();
    if (int(n.idx.size()) > max_leaf && n.depth < max_depth) {
      const double half = 0.5 * n.size;
      const Vec3 mid = n.lo + Vec3::Constant(half);
      std::array<std::vector<int>, 8> part;
      for (int i : n.idx) {
        const Vec3& p = points[size_t(i)];
        part[size_t((p.x() >= mid.x()) + 2 * (p.y() >= mid.y()) + 4 * (p.z() >= mid.z()))].push_back(i);
      }
      const int first = int(g.nodes_.size());
      g.nodes_[size_t(n.node)].first = first;
      g.nodes_.resize(g.nodes_.size() + 8);
      for (int o = 7; o >= 0; --o) {  // pushed in reverse: octant 0 is handled first
        const Vec3 lo(o & 1 ? mid.x() : n.lo.x(), o & 2 ? mid.y() : n.lo.y(), o & 4 ? mid.z() : n.lo.z());
        stack.push_back({first + o, std::move(part[size_t(o)]), lo, half, n.depth + 1});
      }
      continue;
    }
    double sum = 0;
    for (int i : n.idx) sum += std::isfinite(values[size_t(i)]) && values[size_t(i)] > 0 ? values[size_t(i)] : 0.0;
    const double mean = n.idx.empty() ? 0.0 : sum / double(n.idx.size());
    g.nodes_[size_t(n.node)].cell = int(g.lo_.size());
    g.lo_.push_back(n.lo);
    g.size_.push_back(n.size);
    g.cdf_.push_back(g.cdf_.back() + mean * n.size * n.size * n.size);
  }
  if (!(g.cdf_.back() > 0)) g.share_ = 1;  // nothing learnt: uniform
  return g;
}

int SegmentGuide::cell(const Vec3& u) const {
  if (!nodes_.empty()) {
    int n = 0;
    Vec3 lo = Vec3::Zero();
    double size = 1.0;
    while (nodes_[size_t(n)].first >= 0) {
      size *= 0.5;
      const Vec3 mid = lo + Vec3::Constant(size);
      const int ox = u.x() >= mid.x(), oy = u.y() >= mid.y(), oz = u.z() >= mid.z();
      lo = Vec3(ox ? mid.x() : lo.x(), oy ? mid.y() : lo.y(), oz ? mid.z() : lo.z());
      n = nodes_[size_t(n)].first + ox + 2 * oy + 4 * oz;
    }
    return nodes_[size_t(n)].cell;
  }
  if (uniform()) return 0;
  auto index = [&](double x) { return std::clamp(int(x * resolution_), 0, resolution_ - 1); };
  return index(u.x()) + resolution_ * (index(u.y()) + resolution_ * index(u.z()));
}

double SegmentGuide::density(const Vec3& u) const {
  if (uniform() || share_ >= 1) return 1.0;
  const size_t c = size_t(cell(u));
  if (nodes_.empty()) return share_ + (1 - share_) * (cdf_[c + 1] - cdf_[c]) / cdf_.back() * double(cdf_.size() - 1);
  const double volume = size_[c] * size_[c] * size_[c];  // >= 2^-48: no underflow
  return share_ + (1 - share_) * ((cdf_[c + 1] - cdf_[c]) / cdf_.back()) / volume;
}

Vec3 SegmentGuide::sample(double choose, double pick, const Vec3& within) const {
  if (uniform() || share_ >= 1 || choose < share_) return within;
  const double target = pick * cdf_.back();
  const size_t c =
      std::min(size_t(std::upper_bound(cdf_.begin(), cdf_.end(), target) - cdf_.begin()) - 1, cdf_.size() - 2);
  if (!nodes_.empty()) {
    // lo + size is exact (dyadic); rounding of lo + x size must not carry u into the next leaf.
    auto coordinate = [&](double lo, double x) {
      return std::min(lo + x * size_[c], std::nextafter(lo + size_[c], lo));
    };
    return Vec3(coordinate(lo_[c].x(), within.x()), coordinate(lo_[c].y(), within.y()),
                coordinate(lo_[c].z(), within.z()));
  }
  const int r = resolution_;
  const int ix = int(c % size_t(r)), iy = int((c / size_t(r)) % size_t(r)), iz = int(c / (size_t(r) * size_t(r)));
  auto coordinate = [&](int i, double x) { return std::min((i + x) / r, std::nextafter(1.0, 0.0)); };
  return Vec3(coordinate(ix, within.x()), coordinate(iy, within.y()), coordinate(iz, within.z()));
}

void check_projective_guiding(const ProjectiveGuiding& guiding) {
  if (guiding.resolution < 0 || guiding.resolution > 64)
    throw Error("projective: guiding resolution " + std::to_string(guiding.resolution) + " out of range [0, 64]");
  if (guiding.resolution > 0 && guiding.octree)
    throw Error("projective: a guiding resolution and the octree guide exclude each other");
  if (guiding.resolution == 0 && !guiding.octree) return;
  if (guiding.resolution > 0 && !(guiding.training > 0 && guiding.training <= 1024))
    throw Error("projective: guiding training segments per pixel " + std::to_string(guiding.training) +
                " out of range (0, 1024]");
  if (guiding.octree && !(guiding.seeds > 0 && guiding.seeds <= 1024))
    throw Error("projective: guiding seed paths per pixel " + std::to_string(guiding.seeds) +
                " out of range (0, 1024]");
  if (!(guiding.uniform_share > 0 && guiding.uniform_share <= 1))
    throw Error("projective: guiding uniform share " + std::to_string(guiding.uniform_share) + " out of range (0, 1]");
}

SegmentGuide train_segment_guide(const PathContext& ctx, const SceneVelocities& velocities,
                                 const ProjectiveEdges& edges, const ProjectiveGuiding& guiding, int threads,
                                 PathStats& stats) {
  if (guiding.resolution == 0 || edges.empty()) return {};
  const Camera& cam = ctx.scene->camera;
  const size_t cells = size_t(guiding.resolution) * guiding.resolution * guiding.resolution;
  // At least kGuideTrainingPerCell segments per cell: a small image's T W H would leave most cells
  // unvisited and give the few lucky ones all the weight.
  const long long per_pixel = projective_samples_per_index(cam.width, cam.height, guiding.training);
  const long long per_cell = ((long long)(kGuideTrainingPerCell * double(cells)) + ChunkPlan::kChunkSize - 1) /
                             ChunkPlan::kChunkSize * ChunkPlan::kChunkSize;
  const ChunkPlan plan(std::max(per_pixel, per_cell), false, 0, 1, 0, 1, "projective guiding", "training segments");
  // In batches of chunks, each batch in parallel and merged in chunk order (the same guide for
  // any thread count; memory: a batch's sums, not every chunk's).
  constexpr long long kBatch = 16;
  std::vector<std::vector<double>> sums(size_t(std::min(kBatch, plan.chunks)));
  std::vector<PathStats> chunk_stats(sums.size());
  std::vector<double> weights(cells, 0.0);
  const SegmentContext sc(ctx, velocities, edges);
  for (long long j0 = 0; j0 < plan.chunks; j0 += kBatch) {
    const long long j1 = std::min(plan.chunks, j0 + kBatch);
    plan.run(
        threads,
        [&](long long j, long long count, long long c) {
          std::vector<double>& mine = sums[size_t(j - j0)];
          mine.assign(cells, 0.0);
          chunk_stats[size_t(j - j0)] = PathStats{};
          with_dual_size(velocities.num_params, [&](auto n) {
            train_chunk<decltype(n)::value>(sc, guiding.resolution, count, c, mine, chunk_stats[size_t(j - j0)]);
          });
        },
        j0, j1);
    for (long long j = j0; j < j1; ++j) {
      const std::vector<double>& mine = sums[size_t(j - j0)];
      for (size_t c = 0; c < cells; ++c) weights[c] += mine[c];
      stats.rays += chunk_stats[size_t(j - j0)].rays;
    }
  }
  return SegmentGuide(guiding.resolution, weights, guiding.uniform_share);
}

SegmentGuide train_projected_guide(const PathContext& ctx, const SceneVelocities& velocities,
                                   const ProjectiveEdges& edges, const ProjectiveGuiding& guiding, int threads,
                                   PathStats& stats, long long* seeds) {
  if (seeds) *seeds = 0;
  if (!guiding.octree || edges.empty()) return {};
  const Camera& cam = ctx.scene->camera;
  const TriangleEdges tri = triangle_edges(*ctx.scene, edges);
  const long long paths = projective_samples_per_index(cam.width, cam.height, guiding.seeds);
  if (paths > kMaxSeedPaths) {
    char buf[200];
    std::snprintf(buf, sizeof buf,
                  "projective: %g guiding seed paths per pixel at %dx%d are %lld paths, more than %lld; lower "
                  "--guiding-seeds",
                  guiding.seeds, cam.width, cam.height, paths, kMaxSeedPaths);
    throw Error(buf);
  }
  const ChunkPlan plan(paths, false, 0, 1, 0, 1, "projective guiding", "seed paths");
  std::vector<std::vector<std::pair<Vec3, double>>> found{size_t(plan.chunks)};
  std::vector<PathStats> chunk_stats{size_t(plan.chunks)};
  const SegmentContext sc(ctx, velocities, edges);
  plan.run(threads, [&](long long j, long long count, long long c) {
    with_dual_size(velocities.num_params, [&](auto n) {
      seed_chunk<decltype(n)::value>(sc, tri, count, c, found[size_t(j)], chunk_stats[size_t(j)]);
    });
  });
  size_t total = 0;
  for (const auto& f : found) total += f.size();
  std::vector<Vec3> points;
  std::vector<double> values;
  points.reserve(total);
  values.reserve(total);
  for (size_t j = 0; j < found.size(); ++j) {
    for (const auto& [u, v] : found[j]) {
      points.push_back(u);
      values.push_back(v);
    }
    std::vector<std::pair<Vec3, double>>().swap(found[j]);  // freed as it is copied
    stats.rays += chunk_stats[j].rays;
  }
  if (seeds) *seeds = (long long)points.size();
  if (points.empty()) return {};
  return SegmentGuide::octree(points, values, kOctreeMaxDepth, kOctreeMaxLeaf, guiding.uniform_share);
}

uint64_t add_projective_boundary(Film& film, const PathContext& ctx, const SceneVelocities& velocities,
                                 const ProjectiveEdges& edges, const SegmentGuide& guide, double ratio,
                                 int first_sample, int spp, uint64_t seed, int threads, PathStats& stats, int part,
                                 int parts, std::vector<FilmSplat>* deferred) {
  const Camera& cam = ctx.scene->camera;
  const ChunkPlan plan(projective_samples_per_index(cam.width, cam.height, ratio), edges.empty(), first_sample, spp,
                       part, parts, "projective boundary term", "--sppi");
  std::vector<std::vector<FilmSplat>> splats{static_cast<size_t>(plan.chunks)};
  std::vector<PathStats> chunk_stats{static_cast<size_t>(plan.chunks)};
  std::vector<uint64_t> nonfinite(static_cast<size_t>(plan.chunks), 0);
  const SegmentContext sc(ctx, velocities, edges);
  plan.run(threads, [&](long long j, long long count, long long c) {
    with_dual_size(velocities.num_params, [&](auto n) {
      nonfinite[size_t(j)] = run_chunk<decltype(n)::value>(sc, guide, count, plan.per_sample, seed, c,
                                                           splats[size_t(j)], chunk_stats[size_t(j)]);
    });
  });
  merge_chunk_splats(splats, chunk_stats, film, stats, deferred);
  uint64_t total = 0;
  for (uint64_t n : nonfinite) total += n;
  return total;
}

}  // namespace qsil
