/// @file primary_boundary.cpp
/// See primary_boundary.h.

#include "integrators/primary_boundary.h"

#include "qsil/edgetree/mesh_edges.h"
#include "qsil/integrators/boundary_term.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>

namespace qsil {

namespace {

/// Camera-space position of world point x (camera looks along +z).
Vec3 to_camera(const Camera& cam, const Vec3& x) {
  return cam.to_world.block<3, 3>(0, 0).transpose() * (x - cam.origin());
}

/// Clips the camera-space segment c0 + t (c1 - c0), t in [ta, tb], to the half space n.c >= d.
bool clip(const Vec3& c0, const Vec3& c1, const Vec3& n, double d, double& ta, double& tb) {
  const double f0 = n.dot(c0) - d, f1 = n.dot(c1) - d;
  if (f0 < 0 && f1 < 0) return false;
  if (f0 >= 0 && f1 >= 0) return true;
  const double tc = f0 / (f0 - f1);  // the crossing
  if (f0 < 0) ta = std::max(ta, tc);
  else tb = std::min(tb, tc);
  return ta < tb;
}

/// Splats of one chunk of primary samples: (pixel, channel, value).
struct Splat {
  int x, y, channel;
  double value;
};

template <int N>
void run_chunk(const PathContext& ctx, const SceneVelocities& vel, const std::vector<PrimaryEdge>& edges,
               const std::vector<double>& cdf, long long first, long long count, double per_sample, uint64_t seed,
               long long chunk, std::vector<Splat>& out, PathStats& stats) {
  const Camera& cam = ctx.scene->camera;
  const Vec2 tanf = cam.tan_half_fov();
  const double fx = cam.width / (2.0 * tanf.x()), fy = cam.height / (2.0 * tanf.y());
  const Vec3 o = cam.origin();
  const Vec3 forward = cam.to_world.block<3, 1>(0, 2).normalized();
  const int K = vel.num_params;
  const Eigen::Matrix<double, 3, N> dp = Eigen::Matrix<double, 3, N>::Zero();  // the camera does not move
  Sampler sampler(seed, uint64_t(chunk), 0, 2);
  for (long long i = first; i < first + count; ++i) {
    ++stats.boundary_traversals;
    // ---- An edge by its weight (projected length, less for creases), a point uniformly along
    // its projected segment.
    const double u = sampler.next() * cdf.back();
    const size_t j = std::min(size_t(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin()) - 1, edges.size() - 1);
    const PrimaryEdge& pe = edges[j];
    const double s = sampler.next();
    const double tp = s * pe.za / (pe.zb * (1 - s) + s * pe.za);                 // perspective-correct
    const double dsdt = pe.za * pe.zb / std::pow((1 - tp) * pe.za + tp * pe.zb, 2);  // ds/dt'
    const double t = pe.ta + tp * (pe.tb - pe.ta);
    const double pdf = (pe.weight / cdf.back()) * dsdt / (pe.tb - pe.ta);
    const Vec2 film = pe.a + s * (pe.b - pe.a);
    const int px = std::clamp(int(film.x()), 0, cam.width - 1), py = std::clamp(int(film.y()), 0, cam.height - 1);
    // ---- W(w) = f_x f_y / cos^3: pixels^2 per steradian of the box-filtered pixel.
    const Vec3 w = (pe.edge->p0 + t * (pe.edge->p1 - pe.edge->p0) - o).normalized();
    const double cos_theta = w.dot(forward);
    if (!(cos_theta > 0) || !(pdf > 0)) {
      ++stats.boundary_zero;
      continue;
    }
    const double W = fx * fy / (cos_theta * cos_theta * cos_theta);
    Color jump;
    Eigen::Matrix<double, 1, N> J;
    if (!edge_jump<N>(ctx, vel, *pe.edge, t, o, o, false, dp, 0, sampler, stats, jump, J) || (jump == 0).all()) {
      ++stats.boundary_zero;
      continue;
    }
    const Color weight = jump * (W * per_sample / pdf);
    for (int k = 0; k < K; ++k) {
      for (int c = 0; c < 3; ++c) out.push_back({px, py, 3 * (1 + k) + c, weight[c] * J[k]});
      out.push_back({px, py, 3 * (1 + K) + k, weight.mean() * J[k]});
    }
  }
}

}  // namespace

Vec2 project_to_film(const Camera& cam, const Vec3& x, double* depth) {
  const Vec3 c = to_camera(cam, x);
  const Vec2 t = cam.tan_half_fov();
  if (depth) *depth = c.z();
  return Vec2(0.5 * cam.width * (1.0 - c.x() / (c.z() * t.x())), 0.5 * cam.height * (1.0 - c.y() / (c.z() * t.y())));
}

std::vector<PrimaryEdge> find_primary_edges(const Scene& scene, const edgetree::EdgeForest& forest,
                                            const std::vector<bool>& moving) {
  const Camera& cam = scene.camera;
  const Vec3 o = cam.origin();
  const Vec2 tf = cam.tan_half_fov();
  std::vector<PrimaryEdge> out;
  // Silhouettes and boundary edges from o, and every crease of a flat-shaded shape (its two
  // faces both seen: the shading jumps across it).
  auto consider = [&](const edgetree::ForestEdge& e) {
    if (e.shape >= int(moving.size()) || !moving[e.shape]) return;
    if (!edgetree::is_discontinuity(e, o)) return;
    const Vec3 c0 = to_camera(cam, e.p0), c1 = to_camera(cam, e.p1);
    PrimaryEdge pe;
    pe.edge = &e;
    // Near plane and the four side planes of the frustum (camera space).
    if (!clip(c0, c1, Vec3(0, 0, 1), cam.near_clip, pe.ta, pe.tb)) return;
    if (!clip(c0, c1, Vec3(-1, 0, tf.x()), 0, pe.ta, pe.tb)) return;
    if (!clip(c0, c1, Vec3(1, 0, tf.x()), 0, pe.ta, pe.tb)) return;
    if (!clip(c0, c1, Vec3(0, -1, tf.y()), 0, pe.ta, pe.tb)) return;
    if (!clip(c0, c1, Vec3(0, 1, tf.y()), 0, pe.ta, pe.tb)) return;
    pe.a = project_to_film(cam, e.p0 + pe.ta * (e.p1 - e.p0), &pe.za);
    pe.b = project_to_film(cam, e.p0 + pe.tb * (e.p1 - e.p0), &pe.zb);
    pe.length = (pe.b - pe.a).norm();
    pe.weight = pe.length * (e.crease ? std::max(e.angle, 1e-3) / kPi : 1.0);
    if (pe.weight > 0 && pe.za > 0 && pe.zb > 0) out.push_back(pe);
  };
  for (const auto& e : forest.edges()) consider(e);
  for (const auto& e : forest.always_edges()) consider(e);
  return out;
}

void add_primary_boundary(Film& film, const PathContext& ctx, const SceneVelocities& velocities,
                          const std::vector<PrimaryEdge>& edges, long long num_samples, int spp, uint64_t seed,
                          int threads, PathStats& stats) {
  if (edges.empty() || num_samples <= 0) return;
  std::vector<double> cdf(1, 0.0);
  for (const auto& e : edges) cdf.push_back(cdf.back() + e.weight);
  // Each sample estimates the whole image's primary term; a pixel's film mean divides by spp.
  const double per_sample = double(spp) / double(num_samples);
  const long long chunk_size = 1024;
  const long long chunks = (num_samples + chunk_size - 1) / chunk_size;
  std::vector<std::vector<Splat>> splats{static_cast<size_t>(chunks)};
  std::vector<PathStats> chunk_stats{static_cast<size_t>(chunks)};
  const int K = velocities.num_params;
  auto body = [&](long long c) {
    const long long first = c * chunk_size, count = std::min(chunk_size, num_samples - first);
    auto& out = splats[size_t(c)];
    auto& st = chunk_stats[size_t(c)];
    if (K == 1) run_chunk<1>(ctx, velocities, edges, cdf, first, count, per_sample, seed, c, out, st);
    else if (K == 2) run_chunk<2>(ctx, velocities, edges, cdf, first, count, per_sample, seed, c, out, st);
    else if (K <= 4) run_chunk<4>(ctx, velocities, edges, cdf, first, count, per_sample, seed, c, out, st);
    else run_chunk<8>(ctx, velocities, edges, cdf, first, count, per_sample, seed, c, out, st);
  };
  auto run = [&] { tbb::parallel_for(0LL, chunks, body); };
  if (threads > 0) tbb::task_arena(threads).execute(run);
  else run();
  // Merge in chunk order: the same sums whatever the thread count.
  for (long long c = 0; c < chunks; ++c) {
    for (const Splat& s : splats[size_t(c)]) film.splat(s.x, s.y, s.channel, s.value);
    stats.rays += chunk_stats[size_t(c)].rays;
    stats.boundary_traversals += chunk_stats[size_t(c)].boundary_traversals;
    stats.boundary_zero += chunk_stats[size_t(c)].boundary_zero;
  }
}

}  // namespace qsil
