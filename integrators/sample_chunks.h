#pragma once
/// @file sample_chunks.h
/// Boundary-term samples that are not drawn per pixel but over the whole image and splatted where
/// they land (the primary boundary term, primary_boundary.h; projective sampling's boundary
/// segments, projective_boundary.h): numbered globally, n per sample index, and drawn in chunks of
/// 1024 numbers, chunk c from its own stream whichever run draws it. n is a whole number of chunks,
/// so no chunk straddles two sample indices and the sample-range guarantees of estimator.h hold:
/// runs over ranges that partition [0, spp) draw exactly the samples of the run over [0, spp).

#include "pixel_loop.h"
#include "qsil/check.h"
#include "qsil/error.h"
#include "qsil/film.h"
#include "qsil/integrators/path_tracer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <string>
#include <vector>

namespace qsil {

/// The chunks of samples [first_sample, first_sample + spp) of a splatted term drawing
/// `per_index` samples per sample index (a multiple of kChunkSize), and part `part` of `parts`'
/// share of them: a contiguous run of chunks, in order.
struct ChunkPlan {
  double per_sample = 0;         ///< each sample estimates the whole image's term; a pixel's mean divides by spp
  long long g0 = 0, g1 = 0;      ///< global sample numbers of the range
  long long c0 = 0, chunks = 0;  ///< this part's first chunk and chunk count
  static constexpr long long kChunkSize = 1024;
  /// `empty`: the term has nothing to sample (no chunk runs). `what` names the term in the error
  /// thrown when the numbering would overflow ("TERM: N samples per sample index up to sample S
  /// overflow its numbering (OPTION)", `fewer` naming the option that lowers N).
  ChunkPlan(long long per_index, bool empty, int first_sample, int spp, int part, int parts, const std::string& what,
            const std::string& fewer) {
    QSIL_DCHECK(per_index % kChunkSize == 0);
    if (!(double(per_index) * (double(first_sample) + double(spp)) < 0x1p62))
      throw Error(what + ": " + std::to_string(per_index) + " samples per sample index up to sample " +
                  std::to_string(first_sample + spp) + " overflow its numbering (fewer " + fewer + ")");
    const long long num_samples = per_index * spp;
    per_sample = double(spp) / double(std::max(1LL, num_samples));
    // Sample index s owns samples [s n, (s + 1) n), n a whole number of chunks; chunk c holds
    // numbers [c 1024, (c + 1) 1024): no range starts inside a chunk.
    g0 = per_index * first_sample;
    g1 = g0 + num_samples;
    const long long first_chunk = g0 / kChunkSize, all_chunks = (g1 + kChunkSize - 1) / kChunkSize - first_chunk;
    c0 = first_chunk + all_chunks * part / parts;
    chunks = first_chunk + all_chunks * (part + 1) / parts - c0;
    if (empty || num_samples <= 0) chunks = 0;
  }
  /// Runs body(j, count, chunk) in parallel for chunks j in [j0, j1) of this part (default: all):
  /// `count` samples of global chunk `chunk` (a whole chunk: ranges start at a chunk's start).
  template <class Body>
  void run(int threads, Body&& body, long long j0 = 0, long long j1 = -1) const {
    QSIL_DCHECK(g0 % kChunkSize == 0);
    auto one = [&](long long j) {
      const long long c = c0 + j;
      const long long begin = std::max(g0, c * kChunkSize), end = std::min(g1, (c + 1) * kChunkSize);
      body(j, end - begin, c);
    };
    in_arena(threads, [&] { tbb::parallel_for(j0, j1 < 0 ? chunks : j1, one); });
  }
};

/// Hands on the splats and counters of a plan's chunks in chunk order (the same sums whatever the
/// thread count): into `film`, or, with `deferred`, appended there in that order.
inline void merge_chunk_splats(std::vector<std::vector<FilmSplat>>& splats, const std::vector<PathStats>& chunk_stats,
                               Film& film, PathStats& stats, std::vector<FilmSplat>* deferred) {
  for (size_t c = 0; c < splats.size(); ++c) {
    if (deferred) {
      deferred->insert(deferred->end(), splats[c].begin(), splats[c].end());
      std::vector<FilmSplat>().swap(splats[c]);
    } else {
      for (const FilmSplat& s : splats[c]) film.splat(s.x, s.y, s.channel, s.value);
    }
    stats.rays += chunk_stats[c].rays;
    stats.boundary_traversals += chunk_stats[c].boundary_traversals;
    stats.boundary_zero += chunk_stats[c].boundary_zero;
  }
}

}  // namespace qsil
