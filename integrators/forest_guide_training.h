#pragma once
/// @file forest_guide_training.h
/// The training passes of the forest guide (forest_guiding.h, qsil/edgetree/forest_guide.h):
/// forward-mode gradient paths with the boundary term whose contributing edge points are recorded
/// instead of added to an image.

#include "pixel_loop.h"
#include "qsil/integrators/boundary_hook.h"
#include "qsil/integrators/forest_guiding.h"
#include "qsil/integrators/geometry_view.h"
#include "qsil/integrators/path_tracer.h"

#include <tbb/enumerable_thread_specific.h>

#include <vector>

namespace qsil {

/// The streams of the training passes: the path's Sampler(kForestGuideSeed, pixel, round x spp +
/// s) and its boundary term's boundary_stream(kForestGuideSeed, pixel, round x spp + s), as a run's
/// streams with its seed, so the guide depends on the scene and the options alone.
inline constexpr uint64_t kForestGuideSeed = 0x51a7e5eed0f0ea57ULL;

/// One training pass (round `round`) of `spp` samples per pixel over `ctx`'s camera image: the
/// paths of forward mode (DualView<N> over `vel`) with boundary_ctx's boundary term (its guide as
/// it stands, boundary_ctx.guide set: the traversal then reports the guided slots), on
/// `threads` threads (0: all cores). Returns the records (edgetree::GuideRecord) in tile order,
/// independent of the thread count. Adds the pass's counters to `stats`.
template <int N>
std::vector<edgetree::GuideRecord> forest_guide_pass(const PathContext& ctx, const BoundaryContext& boundary_ctx,
                                                     const SceneVelocities& vel, int spp, int round, int threads,
                                                     PathStats& stats) {
  const Camera& cam = ctx.scene->camera;
  const Vec3 origin = cam.origin();
  const DualView<N> view{ctx.scene, &vel};
  std::vector<std::vector<edgetree::GuideRecord>> per_tile(size_t(tile_count(cam.width, cam.height)));
  tbb::enumerable_thread_specific<edgetree::EdgeChoiceScratch> scratch;
  tbb::enumerable_thread_specific<PathStats> tile_stats;
  for_each_tile(cam.width, cam.height, threads, "", [&](const Tile& tile) {
    std::vector<edgetree::GuideRecord>& records = per_tile[size_t(tile.index)];
    PathStats& st = tile_stats.local();
    for (int y = tile.y0; y < tile.y1; ++y)
      for (int x = tile.x0; x < tile.x1; ++x) {
        const uint64_t pixel = uint64_t(y) * cam.width + x;
        for (int s = 0; s < spp; ++s) {
          const uint64_t index = uint64_t(round) * uint64_t(spp) + uint64_t(s);
          Sampler sampler(kForestGuideSeed, pixel, index);
          Sampler bsampler = boundary_stream(kForestGuideSeed, pixel, index);
          const int traversals = boundary_traversals(boundary_ctx.sppi, kForestGuideSeed, pixel, index);
          const CameraRay ray = trace_camera_ray(ctx, x, y, sampler.next2(), st);
          if (traversals <= 0) continue;
          BoundaryHook<N> hook{{&ctx, &boundary_ctx, &bsampler, traversals, &scratch.local()}};
          hook.guide_records = &records;
          trace_path(ctx, view, {lift<Dual<N>>(origin), ray.dir, ray.hit}, sampler, st, hook);
        }
      }
  });
  for (const PathStats& st : tile_stats) stats += st;
  std::vector<edgetree::GuideRecord> out;
  for (const std::vector<edgetree::GuideRecord>& r : per_tile) out.insert(out.end(), r.begin(), r.end());
  return out;
}

}  // namespace qsil
