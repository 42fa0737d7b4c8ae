#pragma once
/// @file pixel_loop.h
/// Parallel loops over the pixels of an image with oneTBB, with a progress bar on stderr for runs
/// longer than a second. Each pixel is processed by exactly one task, and its samples are drawn
/// from streams seeded by (seed, pixel, sample index), so results do not depend on the thread
/// count, and a run over a sample range draws exactly the samples of that range.

#include "qsil/film.h"
#include "qsil/integrators/estimator.h"
#include "qsil/integrators/path_tracer.h"
#include "qsil/rng.h"

#include <tbb/enumerable_thread_specific.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <string>
#include <type_traits>
#include <vector>

namespace qsil {

/// Runs `run` (which may run parallel TBB work) on `threads` threads (0 = all cores: the caller's
/// arena).
void in_arena(int threads, const std::function<void()>& run);

/// The side of a tile of pixels (for_each_tile).
inline constexpr int kTileSize = 16;

/// A tile of pixels [x0, x1) x [y0, y1), kTileSize on a side but at the image's right and bottom
/// borders; tiles are numbered row by row (`index`), which is the order results summed per tile
/// are combined in (independent of the thread count).
struct Tile {
  int index, x0, y0, x1, y1;
};

/// Number of tiles of a width x height image.
int tile_count(int width, int height);

/// Calls body(tile) for every tile of a width x height image, each once, in parallel on `threads`
/// threads (0 = all cores). `label` prefixes the progress bar ("" = no bar).
void for_each_tile(int width, int height, int threads, const std::string& label,
                   const std::function<void(const Tile& tile)>& body);

/// Calls body(x, y) for every pixel of a width x height image, in parallel over its tiles on
/// `threads` threads (0 = all cores). `label` prefixes the progress bar ("" = no bar). With
/// parts > 1 only for the pixels of part `part` (Film::part_of), in parallel over runs of them.
void for_each_pixel(int width, int height, int threads, const std::string& label,
                    const std::function<void(int x, int y)>& body, int part = 0, int parts = 1);

/// One estimator run over samples [first, first + count) of every pixel of `camera`'s image:
/// `sample(x, y, s, sampler, stats, out)` fills out[0 .. layout.channels()) for sample s of
/// pixel (x, y), drawing from `sampler` = Sampler(seed, pixel, s), and returns nothing or the
/// sample's stratum (0 or 1, Film::add_sample: samples of a pixel drawn unalike; 1 only with a
/// `stratum_fraction` > 0, the film's, the share of stratum 1), for the pixels of part
/// options.part of options.parts (every pixel when parts = 1). A sample with a non-finite
/// value is replaced by zeros and counted. Fills result.film, spp, first_sample, seconds, rays and
/// nonfinite; adds every thread's counters to `total`.
template <class SampleFn>
void run_pixels(const Camera& camera, const FilmLayout& layout, const RenderOptions& options, int first, int count,
                const std::string& label, SampleFn&& sample, RenderResult& result, PathStats& total,
                double stratum_fraction = 0.0) {
  const int W = camera.width, H = camera.height;
  const int channels = layout.channels();
  result.film = Film(W, H, layout, stratum_fraction);
  result.first_sample = first;
  result.spp = count;
  tbb::enumerable_thread_specific<PathStats> stats;
  std::atomic<uint64_t> nonfinite{0};
  const auto t0 = std::chrono::steady_clock::now();
  for_each_pixel(
      W, H, options.threads, options.progress ? label : "",
      [&](int x, int y) {
        std::vector<double> out(static_cast<size_t>(channels));
        PathStats& st = stats.local();
        const uint64_t pixel = uint64_t(y) * W + x;
        for (int s = first; s < first + count; ++s) {
          Sampler sampler(options.seed, pixel, uint64_t(s));
          int stratum = 0;
          if constexpr (std::is_void_v<decltype(sample(x, y, s, sampler, st, out.data()))>)
            sample(x, y, s, sampler, st, out.data());
          else
            stratum = sample(x, y, s, sampler, st, out.data());
          bool finite = true;
          for (double v : out) finite = finite && std::isfinite(v);
          if (!finite) {
            nonfinite.fetch_add(1);
            std::fill(out.begin(), out.end(), 0.0);
          }
          result.film.add_sample(x, y, out.data(), stratum);
        }
      },
      options.part, options.parts);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (const PathStats& st : stats) {
    result.rays += st.rays;
    total += st;
  }
  result.nonfinite = nonfinite.load();
}

}  // namespace qsil
