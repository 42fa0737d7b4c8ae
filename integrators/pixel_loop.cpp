/// @file pixel_loop.cpp
/// See pixel_loop.h.

#include "pixel_loop.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <mutex>
#include <string>

namespace qsil {

namespace {

/// A progress bar on stderr for runs longer than a second, updated at most every 250 ms by
/// whichever thread finishes work; "" = none.
class ProgressBar {
 public:
  ProgressBar(std::string label, long long total) : label_(std::move(label)), total_(total) {}
  ~ProgressBar() {
    if (printed_) std::fprintf(stderr, "\r%s [##############################] 100.0%%\n", label_.c_str());
  }
  /// `n` more units of work are done.
  void advance(long long n) {
    const long long d = done_.fetch_add(n) + n;
    if (label_.empty()) return;
    const auto now = clock::now();
    if (now - start_ < std::chrono::seconds(1)) return;
    std::unique_lock lock(print_mutex_, std::try_to_lock);
    if (!lock.owns_lock() || now - last_print_ < std::chrono::milliseconds(250)) return;
    last_print_ = now;
    const int width_bar = 30;
    const double frac = double(d) / double(total_);
    const int filled = int(frac * width_bar);
    std::fprintf(stderr, "\r%s [%.*s%*s] %5.1f%%", label_.c_str(), filled, "##############################",
                 width_bar - filled, "", 100.0 * frac);
    std::fflush(stderr);
    printed_ = true;
  }

 private:
  using clock = std::chrono::steady_clock;
  std::string label_;
  long long total_;
  clock::time_point start_ = clock::now(), last_print_ = start_;
  std::atomic<long long> done_{0};
  std::mutex print_mutex_;
  std::atomic<bool> printed_{false};
};

}  // namespace

void in_arena(int threads, const std::function<void()>& run) {
  if (threads > 0) {
    tbb::task_arena arena(threads);
    arena.execute(run);
  } else {
    run();
  }
}

int tile_count(int width, int height) {
  return ((width + kTileSize - 1) / kTileSize) * ((height + kTileSize - 1) / kTileSize);
}

void for_each_tile(int width, int height, int threads, const std::string& label,
                   const std::function<void(const Tile&)>& body) {
  const int tiles_x = (width + kTileSize - 1) / kTileSize;
  const int tiles = tile_count(width, height);
  ProgressBar progress(label, (long long)width * height);
  in_arena(threads, [&] {
    tbb::parallel_for(0, tiles, [&](int i) {
      const int x0 = (i % tiles_x) * kTileSize, y0 = (i / tiles_x) * kTileSize;
      const Tile tile{i, x0, y0, std::min(width, x0 + kTileSize), std::min(height, y0 + kTileSize)};
      body(tile);
      progress.advance((long long)(tile.x1 - tile.x0) * (tile.y1 - tile.y0));
    });
  });
}

void for_each_pixel(int width, int height, int threads, const std::string& label,
                    const std::function<void(int, int)>& body, int part, int parts) {
  if (parts <= 1) {
    for_each_tile(width, height, threads, label, [&](const Tile& t) {
      for (int y = t.y0; y < t.y1; ++y)
        for (int x = t.x0; x < t.x1; ++x) body(x, y);
    });
    return;
  }
  // The part's pixels are part, part + parts, ... (Film::part_of), in parallel over runs of them.
  const long long pixels = (long long)width * height;
  const long long total = (pixels - part + parts - 1) / parts;
  ProgressBar progress(label, total);
  in_arena(threads, [&] {
    tbb::parallel_for(tbb::blocked_range<long long>(0, total, 64), [&](const tbb::blocked_range<long long>& r) {
      for (long long i = r.begin(); i < r.end(); ++i) {
        const long long p = part + i * parts;
        body(int(p % width), int(p / width));
      }
      progress.advance((long long)r.size());
    });
  });
}

}  // namespace qsil
