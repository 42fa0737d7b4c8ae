/// @file projective_boundary.cpp
/// See projective_boundary.h.

#include "projective_boundary.h"

#include "qsil/dual.h"
#include "qsil/error.h"
#include "qsil/integrators/edge_jump.h"
#include "qsil/integrators/geometry_view.h"
#include "qsil/sampling.h"
#include "sample_chunks.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <string>

namespace qsil {

namespace {

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

/// Draws `count` boundary segments of chunk `chunk` from Sampler(seed, chunk, 0, 5) and appends
/// their splats (forward mode, N >= the parameter count) to `out`; returns the non-finite ones.
template <int N>
uint64_t run_chunk(const PathContext& ctx, const SceneVelocities& vel, const ProjectiveEdges& edges, long long count,
                   double per_sample, uint64_t seed, long long chunk, std::vector<FilmSplat>& out, PathStats& stats) {
  const Camera& cam = ctx.scene->camera;
  const Vec2 tanf = cam.tan_half_fov();
  const double fx = cam.width / (2.0 * tanf.x()), fy = cam.height / (2.0 * tanf.y());
  const Vec3 o = cam.origin();
  const Vec3 forward = cam.to_world.block<3, 1>(0, 2).normalized();
  const PrimalView pv{ctx.scene};
  const Vec3& local_origin = ctx.tracer->local_origin();
  const int K = vel.num_params;
  const FilmLayout layout(K);
  uint64_t nonfinite = 0;
  std::array<WalkVertex, kUnboundedDepthCap> walk;
  Sampler sampler(seed, uint64_t(chunk), 0, 5);
  for (long long i = 0; i < count; ++i) {
    ++stats.boundary_traversals;
    // ---- The boundary segment: an edge by its weight, t uniform, a direction over its valid ones.
    const double ue = sampler.next() * edges.cdf.back();
    const size_t ei = std::min(size_t(std::upper_bound(edges.cdf.begin(), edges.cdf.end(), ue) - edges.cdf.begin()) - 1,
                               edges.edges.size() - 1);
    const edgetree::Edge& e = *edges.edges[ei];
    const double t = sampler.next();
    const EdgeDirection dir = sample_edge_direction(e, sampler.next2());
    const double pdf = edges.probability(ei) * dir.pdf;  // per unit t and steradian
    const Vec3& w = dir.w;
    if (!(pdf > 0)) {
      ++stats.boundary_zero;
      continue;
    }
    // ---- The shading point p: the first hit from the edge point along -w (not the edge's faces).
    const Vec3 y = e.p0 + t * (e.p1 - e.p0);
    ++stats.rays;
    walk[0].hit = ctx.tracer->intersect(y, -w, kInf, edge_faces(e, false));
    if (!walk[0].hit.valid()) {
      ++stats.boundary_zero;
      continue;
    }
    walk[0].si = make_interaction(pv, walk[0].hit, y, Vec3(-w), local_origin);
    walk[0].wi = w;
    const double s = walk[0].si.t, cos_p = std::abs(walk[0].si.ng.dot(w));
    if (!(s > 0 && cos_p > 0) || !walk[0].si.p.allFinite()) {
      ++stats.boundary_zero;
      continue;
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
        const double cos_theta = -wc.dot(forward);
        const Color f = vertex_bsdf(ctx, si, wc).toward(wi);
        if (cos_theta > 0 && (f != 0).any()) {
          const Vec3 origin = spawn_origin(si, wc);
          ++stats.rays;
          if (!ctx.tracer->occluded(origin, wc, (o - origin).norm() * (1.0 - 1.0 / 4096.0), IgnoreSet{})) {
            ++found;
            if (sampler.next() * found < 1.0) {
              const double We = fx * fy / (cos_theta * cos_theta * cos_theta) * std::abs(si.ng.dot(wc)) / (r * r);
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
        const BSDFSample bs = bsdf_sample(*proposal.bsdf, wi_local, uv);
        if (!bs.valid) break;
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
      continue;
    }
    // ---- The jump at p for the kept connection's depth, and its Jacobian with p's velocity.
    const SurfaceInteraction<double>& p = walk[0].si;
    const Vec3 wo_p = kept.vertex == 0 ? kept.wo_p : Vec3(-walk[1].wi);
    OwnFace own;
    if (e.crossing) {
      own.up = p.ng.dot(wo_p) < 0 ? Vec3(-p.ng) : p.ng;  // crossing_jump
    } else if (e.shape == p.shape) {
      own.face = face_in_plane(ctx.scene->shapes[size_t(e.shape)].mesh, e, p.triangle, p.ng, p.p);
      if (own.face >= 0) own.up = p.ng.dot(wo_p) < 0 ? Vec3(-p.ng) : p.ng;
    }
    const EdgeJumpInputs in{.edge = e,
                            .t = t,
                            .p = p.p,
                            .vis_origin = spawn_origin(p, own.face >= 0 ? Vec3(-own.up) : w),
                            .through_back_faces = leaves_below(p, wo_p, w),
                            .own = own,
                            .segments = kept.vertex + 1};
    const Eigen::Matrix<double, 3, N> dp = shading_point_velocity<N>(ctx, vel, walk, kept.vertex);
    Eigen::Matrix<double, 1, N> J;
    const std::optional<Color> jump = edge_jump_with(ctx, in, sampler, stats, [&](const Vec3& g) {
      J = edge_point_jacobian<N>(vel, e, t, g, dp);
      return !J.isZero(0.0);
    });
    if (!jump || (*jump == 0).all()) {
      ++stats.boundary_zero;
      continue;
    }
    const Color c = kept.weight * *jump * (double(found) * per_sample);
    if (!c.allFinite() || !J.allFinite()) {
      ++nonfinite;
      continue;
    }
    for (int k = 0; k < K; ++k) {
      for (int ch = 0; ch < 3; ++ch) out.push_back({kept.px, kept.py, layout.derivative(k, ch), c[ch] * J[k]});
      out.push_back({kept.px, kept.py, layout.derivative_mean(k), c.mean() * J[k]});
    }
  }
  return nonfinite;
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
  // Frame about the edge: a along n0 (perpendicular to the edge), b = edge x a, turned so that
  // n1 lies at azimuth psi1 in [0, pi]. (n0 . w)(n1 . w) < 0 exactly for azimuths in
  // (pi/2, pi/2 + psi1) and that wedge turned by pi.
  const Vec3 axis = (e.p1 - e.p0).normalized();
  const Vec3 n0 = e.q0.head<3>(), n1 = e.q1.head<3>();
  const Vec3 a = (n0 - n0.dot(axis) * axis).normalized();
  Vec3 b = axis.cross(a);
  double psi1 = std::atan2(n1.dot(b), n1.dot(a));
  if (psi1 < 0) {
    b = -b;
    psi1 = -psi1;
  }
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

uint64_t add_projective_boundary(Film& film, const PathContext& ctx, const SceneVelocities& velocities,
                                 const ProjectiveEdges& edges, double ratio, int first_sample, int spp, uint64_t seed,
                                 int threads, PathStats& stats, int part, int parts, std::vector<FilmSplat>* deferred) {
  const Camera& cam = ctx.scene->camera;
  const ChunkPlan plan(projective_samples_per_index(cam.width, cam.height, ratio), edges.empty(), first_sample, spp,
                       part, parts, "projective boundary term", "--sppi");
  std::vector<std::vector<FilmSplat>> splats{static_cast<size_t>(plan.chunks)};
  std::vector<PathStats> chunk_stats{static_cast<size_t>(plan.chunks)};
  std::vector<uint64_t> nonfinite(static_cast<size_t>(plan.chunks), 0);
  const int K = velocities.num_params;
  plan.run(threads, [&](long long j, long long count, long long c) {
    with_dual_size(K, [&](auto n) {
      nonfinite[size_t(j)] = run_chunk<decltype(n)::value>(ctx, velocities, edges, count, plan.per_sample, seed, c,
                                                           splats[size_t(j)], chunk_stats[size_t(j)]);
    });
  });
  merge_chunk_splats(splats, chunk_stats, film, stats, deferred);
  uint64_t total = 0;
  for (uint64_t n : nonfinite) total += n;
  return total;
}

}  // namespace qsil
