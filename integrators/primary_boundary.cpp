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

/// Clips the camera-space segment c0 + t (c1 - c0), t in [ta, tb], to the half space n.c >= d.
bool clip(const Vec3& c0, const Vec3& c1, const Vec3& n, double d, double& ta, double& tb) {
  const double f0 = n.dot(c0) - d, f1 = n.dot(c1) - d;
  if (f0 < 0 && f1 < 0) return false;
  if (f0 >= 0 && f1 >= 0) return true;
  const double tc = f0 / (f0 - f1);  // the crossing
  if (f0 < 0)
    ta = std::max(ta, tc);
  else
    tb = std::min(tb, tc);
  return ta < tb;
}

template <int N>
void run_chunk(const PathContext& ctx, const SceneVelocities& vel, const std::vector<PrimaryEdge>& edges,
               const std::vector<double>& cdf, long long count, double per_sample, uint64_t seed, long long chunk,
               int range_key, std::vector<FilmSplat>& out, PathStats& stats) {
  const Camera& cam = ctx.scene->camera;
  const Vec2 tanf = cam.tan_half_fov();
  const double fx = cam.width / (2.0 * tanf.x()), fy = cam.height / (2.0 * tanf.y());
  const Vec3 o = cam.origin();
  const Vec3 forward = cam.to_world.block<3, 1>(0, 2).normalized();
  const int K = vel.num_params;
  const FilmLayout layout(K);
  const Eigen::Matrix<double, 3, N> dp = Eigen::Matrix<double, 3, N>::Zero();  // the camera does not move
  Sampler sampler(seed, uint64_t(chunk), uint64_t(range_key), 2);
  for (long long i = 0; i < count; ++i) {
    ++stats.boundary_traversals;
    // ---- An edge by its weight (projected length, less for creases), a point uniformly along
    // its projected segment.
    const double u = sampler.next() * cdf.back();
    const size_t j = std::min(size_t(std::upper_bound(cdf.begin(), cdf.end(), u) - cdf.begin()) - 1, edges.size() - 1);
    const PrimaryEdge& pe = edges[j];
    const double s = sampler.next();
    const double tp = s * pe.za / (pe.zb * (1 - s) + s * pe.za);                     // perspective-correct
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
      for (int c = 0; c < 3; ++c) out.push_back({px, py, layout.derivative(k, c), weight[c] * J[k]});
      out.push_back({px, py, layout.derivative_mean(k), weight.mean() * J[k]});
    }
  }
}

}  // namespace

std::vector<PrimaryEdge> find_primary_edges(const Scene& scene, const edgetree::EdgeSet& edges,
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
    const Vec3 c0 = cam.to_camera(e.p0), c1 = cam.to_camera(e.p1);
    PrimaryEdge pe;
    pe.edge = &e;
    // Near plane and the four side planes of the frustum (camera space).
    if (!clip(c0, c1, Vec3(0, 0, 1), cam.near_clip, pe.ta, pe.tb)) return;
    if (!clip(c0, c1, Vec3(-1, 0, tf.x()), 0, pe.ta, pe.tb)) return;
    if (!clip(c0, c1, Vec3(1, 0, tf.x()), 0, pe.ta, pe.tb)) return;
    if (!clip(c0, c1, Vec3(0, -1, tf.y()), 0, pe.ta, pe.tb)) return;
    if (!clip(c0, c1, Vec3(0, 1, tf.y()), 0, pe.ta, pe.tb)) return;
    pe.a = cam.project(e.p0 + pe.ta * (e.p1 - e.p0), &pe.za);
    pe.b = cam.project(e.p0 + pe.tb * (e.p1 - e.p0), &pe.zb);
    pe.length = (pe.b - pe.a).norm();
    pe.weight = pe.length * (e.crease ? std::max(e.angle, 1e-3) / kPi : 1.0);
    if (pe.weight > 0 && pe.za > 0 && pe.zb > 0) out.push_back(pe);
  };
  for (const auto& e : edges.edges()) consider(e);
  for (const auto& e : edges.always_edges()) consider(e);
  return out;
}

void add_primary_boundary(Film& film, const PathContext& ctx, const SceneVelocities& velocities,
                          const std::vector<PrimaryEdge>& edges, int first_sample, int spp, uint64_t seed, int threads,
                          PathStats& stats, int part, int parts, std::vector<FilmSplat>* deferred) {
  const Camera& cam = ctx.scene->camera;
  const long long per_index = (long long)cam.width * cam.height;  // primary samples per sample index
  const long long num_samples = per_index * spp;
  if (edges.empty() || num_samples <= 0) return;
  std::vector<double> cdf(1, 0.0);
  for (const auto& e : edges) cdf.push_back(cdf.back() + e.weight);
  // Each sample estimates the whole image's primary term; a pixel's film mean divides by spp.
  const double per_sample = double(spp) / double(num_samples);
  // ---- Global numbering: sample index s owns primary samples [s W H, (s + 1) W H); chunk c holds
  // numbers [c 1024, (c + 1) 1024) and draws from stream (seed, c, 0, 2), whichever run draws it.
  // A chunk cut by the start of this range draws its part from (seed, c, first_sample, 2).
  const long long chunk_size = 1024;
  const long long g0 = per_index * first_sample, g1 = g0 + num_samples;
  const long long first_chunk = g0 / chunk_size, all_chunks = (g1 + chunk_size - 1) / chunk_size - first_chunk;
  // ---- This part's share of the chunks: a contiguous run of them, in order.
  const long long c0 = first_chunk + all_chunks * part / parts;
  const long long chunks = first_chunk + all_chunks * (part + 1) / parts - c0;
  std::vector<std::vector<FilmSplat>> splats{static_cast<size_t>(chunks)};
  std::vector<PathStats> chunk_stats{static_cast<size_t>(chunks)};
  const int K = velocities.num_params;
  auto body = [&](long long j) {
    const long long c = c0 + j;
    const long long begin = std::max(g0, c * chunk_size), end = std::min(g1, (c + 1) * chunk_size);
    const int key = begin > c * chunk_size ? first_sample : 0;
    auto& out = splats[size_t(j)];
    auto& st = chunk_stats[size_t(j)];
    with_dual_size(K, [&](auto n) {
      run_chunk<decltype(n)::value>(ctx, velocities, edges, cdf, end - begin, per_sample, seed, c, key, out, st);
    });
  };
  auto run = [&] { tbb::parallel_for(0LL, chunks, body); };
  if (threads > 0)
    tbb::task_arena(threads).execute(run);
  else
    run();
  // Merge in chunk order: the same sums whatever the thread count (or hand them on in that order).
  for (long long c = 0; c < chunks; ++c) {
    if (deferred) {
      deferred->insert(deferred->end(), splats[size_t(c)].begin(), splats[size_t(c)].end());
      std::vector<FilmSplat>().swap(splats[size_t(c)]);
    } else {
      for (const FilmSplat& s : splats[size_t(c)]) film.splat(s.x, s.y, s.channel, s.value);
    }
    stats.rays += chunk_stats[size_t(c)].rays;
    stats.boundary_traversals += chunk_stats[size_t(c)].boundary_traversals;
    stats.boundary_zero += chunk_stats[size_t(c)].boundary_zero;
  }
}

}  // namespace qsil
